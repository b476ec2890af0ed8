"""A step no limit-keeping solver can take says why in plain words, then the detail.

"the limits admit no common point: cannot relax" (and "empty box ...") is what the
policy reports when no step meets every limit. The run's failure now starts with the
cause read off the state: a joint torque beyond its limit (the joint, its torque and
its limit; criterion ``torque``), a joint outside its range whose acceleration limit
cannot turn it back in one sample (where it is, how fast it moves, the limit); a
collision pair closer than its safety distance is in
``tests/collision/test_collision_push_apart.py``. The solver's status and message and
the labels of the limits in conflict follow.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from dualarm_qp.control.rollout import rollout
from dualarm_qp.experiments import build_experiment, parse_config
from dualarm_qp.kinematics.robots import example_robots_dir
from dualarm_qp.task.torques import LoadTorques

pytestmark = pytest.mark.skipif(example_robots_dir() is None,
                                reason="example-robot-data is not installed")

CONFIGS = Path(__file__).resolve().parents[2] / "configs"


def _data(name: str, duration: float = 0.3) -> dict:
    data = yaml.safe_load((CONFIGS / f"{name}.yaml").read_text())
    data["controller"]["duration"] = duration
    return data


def test_a_torque_beyond_its_limit_is_named_before_the_solver_detail() -> None:
    """The follower's elbow (qf3) rated at 80% of what it holds at the start; the check
    before the run is left out, so that the first step meets it."""
    data = _data("ur5_pair_heavy_bar")
    exp = build_experiment(parse_config(data, "heavy"), "heavy")
    s = exp.initial
    tau = LoadTorques(exp.task).torques(s.q_l, s.q_f, s.sigma, s.sigma_leader)[6:]
    data["follower"]["tau_max"][2] = 0.8 * abs(tau[2])
    exp = build_experiment(parse_config(data, "heavy"), "heavy")
    res = rollout(exp.controller(), exp.initial, duration=exp.duration, limits=exp.limits,
                  preflight=False)
    failure = res.failure
    assert failure is not None and failure.criterion == "torque" and failure.sample == 0
    assert failure.amount == pytest.approx(tau[2], rel=1e-12)
    assert failure.limit == pytest.approx(0.8 * abs(tau[2]), rel=1e-12)
    assert failure.message.startswith(
        f"step 0 at t = 0.0000 s: no step keeps every limit: joint qf3 needs "
        f"{abs(tau[2]):.4g} N m at this state (to hold its arm and its share of the load), "
        f"beyond its torque limit of {0.8 * abs(tau[2]):.4g} N m (solver status error: ")
    assert "the limits admit no common point" in failure.message
    assert "conflicting: " in failure.message and "torque qf3 " in failure.message


@pytest.mark.parametrize("policy", ["scale", "stop"])
def test_a_joint_outside_its_range_that_cannot_brake_is_named(policy: str) -> None:
    """The follower's first joint starts 1 deg above its (narrowed) range, moving further
    out at 0.5 rad/s; its acceleration limit (15 rad/s^2) changes its rate by 0.15 rad/s
    in one sample: the box of its rate is empty."""
    data = _data("panda_pair_accel")
    data["controller"]["policy"] = policy
    exp = build_experiment(parse_config(data, "accel"), "accel")
    q1 = float(exp.initial.q_f[0])
    data["follower"]["q_max"] = np.degrees(exp.task.follower.q_max).tolist()
    data["follower"]["q_max"][0] = float(np.degrees(q1) - 1.0)
    exp = build_experiment(parse_config(data, "accel"), "accel")
    controller = exp.controller()
    v = np.zeros(controller.layout.n)
    v[controller.layout.n_l] = 0.5
    res = rollout(controller, exp.initial, duration=exp.duration, limits=exp.limits,
                  initial_rates=v)
    failure = res.failure
    assert failure is not None and failure.criterion == "solver" and failure.sample == 0
    hi = float(exp.task.follower.q_max[0])
    assert failure.message.startswith(
        "step 0 at t = 0.0000 s: no step keeps every limit: joint qf1 is outside its range "
        f"({q1:.4g} rad; range -2.897 .. {hi:.4g} rad) and moves at 0.5 rad/s: its "
        "acceleration limit (15 rad/s^2, 0.15 rad/s per sample) cannot bring its rate to "
        "one its range allows within one sample ("), failure.message
    assert ("conflicting: qf1 lower (acceleration), qf1 upper (joint range))"
            in failure.message)
    detail = "empty box (lower > upper) for qf1" if policy == "scale" else "step infeasible"
    assert detail in failure.message
