"""Infeasible steps in a whole run: the object too fast for the follower's speed limits."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from dualarm_qp.control.controller import DualArmController
from dualarm_qp.control.rollout import RunLimits, rollout
from dualarm_qp.experiments import build_experiment, load_config
from dualarm_qp.kinematics.arm import SerialArm
from dualarm_qp.solvers import get_solver
from dualarm_qp.task.scene import DualArmTask

CONFIG = Path(__file__).resolve().parents[2] / "configs" / "puma_beam_sliding_s7_100.yaml"
QD_SLOW = np.array([0.02, 0.02, 0.02, 0.05, 0.05, 0.05])  # rad/s: too slow for 32 mm/s


def slow_experiment():
    exp = build_experiment(load_config(CONFIG))
    f = exp.task.follower
    slow = SerialArm(f.dh, q_min=f.q_min, q_max=f.q_max, qd_max=QD_SLOW, base=f.base,
                     tool=f.tool, name=f.name)
    exp.task = DualArmTask(exp.task.leader, slow, exp.task.H1, exp.task.surface,
                           exp.task.trajectory)
    import dataclasses

    exp.options = dataclasses.replace(exp.options, velocity_limits=True, grasp_speed_max=0.05)
    return exp


@pytest.mark.parametrize("solver", ["nullspace", "qp:daqp", "sns"])
def test_scale_policy_slows_the_object(solver):
    exp = slow_experiment()
    ctrl = DualArmController(exp.task, get_solver(solver), exp.options,
                             leader_gain=exp.leader_gain, policy="scale")
    # The slowed object needs more than twice the nominal time: raise the cap.
    res = rollout(ctrl, exp.initial, duration=3.0, limits=RunLimits(duration_cap=10.0))
    tr = res.trace
    assert res.completed, res.message
    assert tr.tau[-1] == pytest.approx(3.0, abs=1e-9)  # the whole path, past 3 s of time
    assert tr.t[-1] > 3.0
    assert "scaled" in tr.status
    summary = res.summary()
    assert summary["time_lost_to_scaling_s"] > 0.0
    # The run took longer than the path needs at full speed by the time lost to scaling
    # (whole samples: the last one's shortening where the path ends is no loss).
    dt = exp.options.dt
    needed = dt * np.ceil((tr.tau[-1] - tr.tau[0]) / dt - 1e-9)
    assert tr.t[-1] - tr.t[0] - needed == pytest.approx(summary["time_lost_to_scaling_s"])
    assert summary["time_lost_to_scaling_s"] > 1.0
    for name in ("q_f", "q_l", "grasp", "m", "qf_dot", "scale"):
        assert np.isfinite(getattr(tr, name)).all(), name
    assert np.all(np.abs(tr.qf_dot) <= QD_SLOW + 1e-7)
    assert np.all((tr.scale >= 0) & (tr.scale <= 1))
    assert np.max(tr.closure_pos_err) < 1e-6


def test_relax_policy_keeps_bounds_and_fails_on_the_closure():
    exp = slow_experiment()
    ctrl = DualArmController(exp.task, get_solver("nullspace"), exp.options,
                             leader_gain=exp.leader_gain, policy="relax")
    res = rollout(ctrl, exp.initial, duration=3.0)
    tr = res.trace
    # Relaxing the follower's task keeps its limits but opens the grasp: the run
    # fails on the closure instead of hiding it behind a position-level correction.
    assert not res.completed
    assert res.failure is not None and res.failure.criterion == "closure"
    assert "relaxed" in tr.status
    assert np.all(np.abs(tr.qf_dot) <= QD_SLOW + 1e-7)
    assert np.all(np.abs(np.diff(tr.q_f, axis=0)) / exp.options.dt <= QD_SLOW * (1 + 1e-6))
    assert np.isfinite(tr.q_f).all()
    assert np.all(tr.tau == tr.t)  # relax never slows the object


def test_stop_policy_stops_with_the_conflicting_bounds():
    exp = slow_experiment()
    ctrl = DualArmController(exp.task, get_solver("nullspace"), exp.options,
                             leader_gain=exp.leader_gain, policy="stop")
    res = rollout(ctrl, exp.initial, duration=3.0)
    assert not res.completed
    assert "conflicting bounds" in res.message
    assert np.isfinite(res.trace.q_f).all()
    # Each conflicting bound is named once, and the step counts as infeasible.
    assert res.message.count("conflicting bounds") == 1
    listed = res.message.split("conflicting bounds: ")[1].split(")")[0].split(", ")
    assert len(listed) == len(set(listed))
    assert res.trace.status[-1] == "infeasible"
    assert res.summary()["status_counts"].get("error", 0) == 0


def test_a_path_that_cannot_move_stops_the_run():
    """Speed limits so low that only a stopped object is feasible: the path stalls."""
    exp = slow_experiment()
    f = exp.task.follower
    frozen = SerialArm(f.dh, q_min=f.q_min, q_max=f.q_max, qd_max=np.full(6, 1e-9),
                       base=f.base, tool=f.tool, name=f.name)
    exp.task = DualArmTask(exp.task.leader, frozen, exp.task.H1, exp.task.surface,
                           exp.task.trajectory)
    import dataclasses

    exp.options = dataclasses.replace(exp.options, grasp_speed_max=1e-9)
    ctrl = DualArmController(exp.task, get_solver("nullspace"), exp.options, policy="scale")
    res = rollout(ctrl, exp.initial, duration=3.0, limits=RunLimits(stall_time=0.5))
    assert not res.completed
    assert "path stalled" in res.message
    assert res.trace.t[-1] == pytest.approx(0.5, abs=0.031)
