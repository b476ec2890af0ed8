"""The rollout drives a plant when given one (no simulator needed)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import yaml

from dualarm_qp.control.rollout import rollout
from dualarm_qp.experiments import build_experiment, parse_config
from dualarm_qp.step.state import DualArmState

CONFIGS = Path(__file__).resolve().parents[2] / "configs"


def _experiment(name: str, duration: float):
    data = yaml.safe_load((CONFIGS / name).read_text())
    data["controller"]["duration"] = duration
    return build_experiment(parse_config(data, name), name)


class LaggingPlant:
    """Moves each joint by a share of what was commanded; records what it was told."""

    def __init__(self, share: float) -> None:
        self.share = share
        self.resets: list[tuple[DualArmState, float]] = []
        self.calls = 0

    def reset(self, state, dt):
        self.resets.append((state, dt))

    def advance(self, state, command, dt):
        self.calls += 1
        return DualArmState(state.t + dt * command.scale,
                            state.q_l + self.share * dt * command.ql_dot,
                            state.q_f + self.share * dt * command.qf_dot,
                            state.sigma + self.share * dt * command.m, state.sigma_leader)


def test_each_sample_is_the_state_the_plant_measured():
    exp = _experiment("puma_beam_limits.yaml", 0.31)
    plant = LaggingPlant(0.9)
    result = rollout(exp.controller(), exp.initial, duration=exp.duration, limits=exp.limits,
                     plant=plant)
    tr = result.trace
    assert len(plant.resets) == 1 and plant.resets[0][1] == exp.options.dt
    assert plant.calls == len(tr) - 1
    # The recorded joints are the plant's: 90% of each commanded step.
    np.testing.assert_allclose(tr.q_l[1:] - tr.q_l[:-1],
                               0.9 * exp.options.dt * tr.ql_dot[:-1], atol=1e-15)
    free = rollout(exp.controller(), exp.initial, duration=exp.duration, limits=exp.limits)
    assert not np.allclose(free.trace.q_l[-1], tr.q_l[-1], atol=1e-9)


def test_a_plant_turns_the_position_level_corrections_off():
    exp = _experiment("puma_beam_sliding_s7_100.yaml", 0.31)  # the paper's method
    with_plant = rollout(exp.controller(), exp.initial, duration=exp.duration,
                         limits=exp.limits, plant=LaggingPlant(1.0))
    without = rollout(exp.controller(), exp.initial, duration=exp.duration, limits=exp.limits)
    assert with_plant.summary()["projection"] is False
    assert without.summary()["projection"] is True


def test_a_run_the_preflight_refuses_never_resets_the_plant():
    """The plant's reset (MuJoCo's settle) comes after the preflight checks."""
    name = "puma_beam_leader_near_singular.yaml"  # a waypoint out of the leader's reach
    exp = build_experiment(parse_config(yaml.safe_load((CONFIGS / name).read_text()), name),
                           name)
    plant = LaggingPlant(1.0)
    result = rollout(exp.controller(), exp.initial, duration=exp.duration, limits=exp.limits,
                     plant=plant)
    assert not result.completed and result.failure is not None
    assert result.failure.criterion == "unreachable" and len(result.trace) == 0
    assert plant.resets == [] and plant.calls == 0


class RingingPlant(LaggingPlant):
    """Follows every command, but a follower joint rings about it, growing each sample."""

    def advance(self, state, command, dt):
        moved = super().advance(state, command, dt)
        q_f = moved.q_f.copy()
        q_f[1] += 2e-4 * (-1.8) ** self.calls  # rad
        return DualArmState(moved.t, moved.q_l, q_f, moved.sigma, moved.sigma_leader)


def test_an_error_only_the_plant_made_is_not_blamed_on_the_plan():
    """The measured closure breaks its tolerance, the command followed exactly would not
    have: the failure says the plant did not follow, with no kinematic explanation."""
    exp = _experiment("puma_beam_limits.yaml", 0.31)
    result = rollout(exp.controller(), exp.initial, duration=exp.duration, limits=exp.limits,
                     plant=RingingPlant(1.0))
    assert result.failure is not None and result.failure.criterion == "closure"
    message = result.failure.message
    assert "grasp closure lost" in message and "the plant did not follow the command" in message
    assert "cause:" not in message and "second-order" not in message


def test_an_error_the_plan_made_itself_keeps_its_explanation():
    """The paper's method jumps at its first step: followed exactly, the command breaks
    the closure tolerance itself, so the plan's kinematics are to blame."""
    exp = _experiment("puma_beam_sliding_s7_100.yaml", 0.31)
    result = rollout(exp.controller(), exp.initial, duration=exp.duration, limits=exp.limits,
                     plant=LaggingPlant(1.0))
    assert result.failure is not None and result.failure.criterion == "closure"
    assert "cause: " in result.failure.message
    assert "the plant did not follow" not in result.failure.message
