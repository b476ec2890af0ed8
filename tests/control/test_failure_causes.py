"""A fast object: the tracking goes through the scale policy, and a failure names its cause."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
import yaml

from dualarm_qp.control.controller import DualArmController
from dualarm_qp.control.rollout import RunLimits, rollout
from dualarm_qp.experiments import build_experiment
from dualarm_qp.experiments.config import parse_config
from dualarm_qp.kinematics.arm import SerialArm
from dualarm_qp.solvers import get_solver
from dualarm_qp.task.scene import DualArmTask

CONFIGS = Path(__file__).resolve().parents[2] / "configs"


def fast_beam(speed_mm_s: float, duration: float) -> dict:
    """The beam task with hard limits, the object ``speed_mm_s`` fast."""
    data = yaml.safe_load((CONFIGS / "puma_beam_limits.yaml").read_text())
    data["trajectory"]["velocity"] = [speed_mm_s, 0, 0]
    data["controller"]["duration"] = duration
    return data


def experiment(data: dict):
    return build_experiment(parse_config(data, "fast"), "fast")


@pytest.mark.parametrize("solver", ["nullspace", "qp:daqp"])
def test_a_step_that_would_leave_the_path_is_slowed_instead(solver: str) -> None:
    """800 mm/s: the joints' second-order motion over one 31 ms sample would tear the
    grasp at the first step; the error budget slows the task so every recorded error
    stays inside the tolerance."""
    exp = experiment(fast_beam(800.0, 0.3))
    exp.solver_name = solver
    res = rollout(exp.controller(), exp.initial, duration=exp.duration,
                  limits=dataclasses.replace(exp.limits, duration_cap=3.0))
    tr = res.trace
    assert res.completed, res.message
    assert np.max(tr.closure_pos_err) <= 0.5e-3 + 1e-9
    assert np.max(tr.leader_pos_err) <= 0.5e-3 + 1e-9
    assert "scaled" in tr.status and res.time_lost > 0.0
    # Without the budget the same steps break the closure tolerance.
    bare = DualArmController(exp.task, get_solver(solver), exp.options,
                             leader_gain=exp.leader_gain, policy=exp.policy)
    res_bare = rollout(bare, exp.initial, duration=exp.duration,
                       limits=dataclasses.replace(exp.limits, duration_cap=3.0))
    assert res_bare.failure is not None
    assert res_bare.failure.criterion in ("closure", "tracking")


def test_a_run_slowed_by_the_budget_names_the_tolerance() -> None:
    exp = experiment(fast_beam(800.0, 0.5))
    res = rollout(exp.controller(), exp.initial, duration=exp.duration,
                  limits=dataclasses.replace(exp.limits, duration_cap=1.0))
    assert res.failure is not None and res.failure.criterion == "path_incomplete"
    assert "cause: tolerance: at full speed one step of 0.031 s" in res.message
    assert "smallest singular values: leader" in res.message


def test_a_run_slowed_by_the_speed_limits_names_them() -> None:
    data = yaml.safe_load((CONFIGS / "puma_beam_sliding_s7_100.yaml").read_text())
    exp = experiment(data)
    f = exp.task.follower
    slow = SerialArm(f.dh, q_min=f.q_min, q_max=f.q_max, qd_max=np.full(6, 0.02),
                     base=f.base, tool=f.tool, name=f.name)
    exp.task = DualArmTask(exp.task.leader, slow, exp.task.H1, exp.task.surface,
                           exp.task.trajectory)
    exp.options = dataclasses.replace(exp.options, velocity_limits=True, grasp_speed_max=0.05)
    ctrl = DualArmController(exp.task, get_solver("nullspace"), exp.options,
                             leader_gain=exp.leader_gain, policy="scale")
    res = rollout(ctrl, exp.initial, duration=1.0, limits=RunLimits(duration_cap=1.0))
    assert res.failure is not None and res.failure.criterion == "path_incomplete"
    why = res.message.split("cause: ")[1]
    assert why.startswith("speed limits bind (qf")
    times = float(why.split("needs ")[1].split(" times")[0])
    assert times > 1.0
