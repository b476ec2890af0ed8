"""The leader's own limits, singularities, the path's end and what the controller applies."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from dualarm_qp.control.rollout import RunLimits, rollout
from dualarm_qp.experiments import build_experiment, load_config
from dualarm_qp.experiments.config import parse_config
from dualarm_qp.kinematics.arm import SerialArm
from dualarm_qp.solvers.base import Status, StepSolution
from dualarm_qp.step.problem import StepProblem
from dualarm_qp.task.scene import DualArmTask

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
LIMITS = CONFIGS / "puma_beam_limits.yaml"


def with_leader_speed(exp, qd_max):
    leader = exp.task.leader
    slow = SerialArm(leader.dh, q_min=leader.q_min, q_max=leader.q_max,
                     qd_max=np.full(6, qd_max), base=leader.base, tool=leader.tool,
                     name=leader.name)
    exp.task = DualArmTask(slow, exp.task.follower, exp.task.H1, exp.task.surface,
                           exp.task.trajectory)
    return exp


def short(solver="nullspace", policy=None):
    exp = build_experiment(load_config(LIMITS), solver=solver)
    exp.duration = 1.0
    if policy is not None:
        exp.policy = policy
    return exp


def speed_ratio(q, qd_max, dt):
    return np.max(np.abs(np.diff(q, axis=0)) / dt / qd_max)


@pytest.mark.parametrize("solver", ["nullspace", "qp:daqp"])
def test_leader_speed_limit_slows_the_path_for_both_arms(solver):
    exp = with_leader_speed(short(solver), 0.05)  # the beam task needs about 0.08 rad/s
    res = rollout(exp.controller(), exp.initial, duration=exp.duration,
                  limits=RunLimits(duration_cap=4.0))
    tr = res.trace
    assert res.completed, res.message
    assert np.min(tr.scale) < 1.0  # the leader's limit did the slowing
    assert tr.tau[-1] == pytest.approx(exp.initial.t + exp.duration, abs=1e-12)
    assert tr.t[-1] > exp.duration  # it took longer than the nominal duration
    assert speed_ratio(tr.q_l, 0.05, exp.options.dt) <= 1 + 1e-6
    assert speed_ratio(tr.q_f, exp.task.follower.qd_max, exp.options.dt) <= 1 + 1e-6
    # Both arms slowed together: the grasp closure and the tracking held.
    assert np.max(tr.closure_pos_err) < 1e-4 and np.max(tr.leader_pos_err) < 1e-4


def test_leader_limit_under_stop_names_the_leader_joint():
    exp = with_leader_speed(short("nullspace", policy="stop"), 0.05)
    res = rollout(exp.controller(), exp.initial, duration=exp.duration)
    assert not res.completed
    assert res.failure is not None and res.failure.criterion == "solver"
    assert "ql" in res.message and "leader" in res.message
    assert "singular value" in res.message


def test_a_path_too_slow_for_the_cap_fails_as_incomplete():
    exp = with_leader_speed(short(), 0.02)
    res = rollout(exp.controller(), exp.initial, duration=exp.duration,
                  limits=RunLimits(duration_cap=1.5))
    assert not res.completed
    assert res.failure is not None and res.failure.criterion == "path_incomplete"
    assert 0.0 < res.path_completed < 1.0
    assert res.summary()["path_completed_pct"] == pytest.approx(100 * res.path_completed)


def test_singularity_threshold_warns_or_stops():
    exp = short()
    warn = rollout(exp.controller(), exp.initial, duration=0.2,
                   limits=RunLimits(singular_value_min=0.05))
    assert warn.completed
    assert any("the follower is near a singularity" in w for w in warn.warnings)
    stop = rollout(exp.controller(), exp.initial, duration=0.2,
                   limits=RunLimits(singular_value_min=0.05, singularity_action="stop"))
    assert not stop.completed and stop.failure is not None
    assert stop.failure.criterion == "singularity" and stop.failure.amount < 0.05
    assert "follower" in stop.message


def test_every_sample_records_both_singular_values():
    exp = short()
    tr = rollout(exp.controller(), exp.initial, duration=0.2).trace
    for name, arm in (("sigma_min_l", exp.task.leader), ("sigma_min_f", exp.task.follower)):
        q = tr.q_l if name == "sigma_min_l" else tr.q_f
        expected = [np.linalg.svd(arm.jacobian(qk), compute_uv=False)[-1] for qk in q]
        np.testing.assert_allclose(getattr(tr, name), expected, rtol=1e-12)


class BrokenEquality:
    """A solver whose answer breaks A x = b (and so is never integrated)."""

    name = "broken"

    def solve(self, problem: StepProblem) -> StepSolution:
        return StepSolution(x=problem.center + 1.0, status=Status.OPTIMAL, solver=self.name)


def test_a_violation_with_a_broken_equality_is_never_applied():
    exp = short("reference")
    ctrl = exp.controller()
    ctrl.solver = BrokenEquality()
    out = ctrl.step(exp.initial)
    assert out.status is Status.VIOLATION
    assert not out.applied
    assert np.all(out.qf_dot == 0.0) and out.m == 0.0
    # The paper's own step breaks only bounds at Table 2's start: it is applied.
    ok = exp.controller().step(exp.initial)
    assert ok.applied


def test_scale_max_slows_the_feed_forward_only():
    exp = short()
    ctrl = exp.controller()
    full = ctrl.step(exp.initial)
    ctrl.reset()
    half = ctrl.step(exp.initial, scale_max=0.5)
    assert half.scale == pytest.approx(0.5 * full.scale)
    with pytest.raises(ValueError, match="scale_max"):
        ctrl.step(exp.initial, scale_max=1.5)


def test_curved_bar_grasp_outside_its_arc_range_recovers():
    """The curved bar's grasp range is along the arc: a start outside it is not empty."""
    data = yaml.safe_load((CONFIGS / "curved_bar_waypoints.yaml").read_text())
    data["object"]["grasp_initial"] = 420  # mm; the range is 0..400 mm along the arc
    exp = build_experiment(parse_config(data, "curved"))
    res = rollout(exp.controller(), exp.initial, duration=1.0)
    assert res.failure is None or res.failure.criterion != "solver", res.message
    g = res.trace.grasp
    assert np.all(np.diff(g[g > 0.4]) <= 1e-12)  # never further out
    assert g.min() < 0.4  # and back inside


def test_no_time_is_lost_when_only_the_path_end_shortens_the_last_sample():
    exp = short()
    res = rollout(exp.controller(), exp.initial, duration=0.05)  # 1.6 samples of 31 ms
    assert res.completed, res.message
    assert res.summary()["time_lost_to_scaling_s"] == 0.0
    assert res.trace.tau[-1] == pytest.approx(0.05, abs=1e-12)


def test_a_step_that_raises_keeps_the_state_it_failed_at():
    exp = with_leader_speed(short("nullspace", policy="stop"), 0.05)
    res = rollout(exp.controller(), exp.initial, duration=exp.duration)
    assert not res.completed and res.failure is not None
    tr = res.trace
    assert len(tr) == res.failure.sample + 1  # the failing state is the last row
    assert tr.status[-1] == "infeasible" and tr.scale[-1] == 0.0
    assert np.isfinite(tr.q_l).all() and np.isfinite(tr.q_f).all()
