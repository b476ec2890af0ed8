"""How recorded torques decide a run: unknown torques, the limit named, a plant's run.

configs/ur5_pair_heavy_bar.yaml, shortened. A plant (the simulator's place in the
rollout) gives measured states: a torque beyond the limit there is a warning, not the
run's failure, as the other realised limits are; without a plant it fails the run with
criterion ``torque`` naming the joint and its limit.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
import yaml

from dualarm_qp.control.rollout import rollout, torque_failure
from dualarm_qp.experiments import build_experiment, parse_config
from dualarm_qp.kinematics.robots import example_robots_dir
from dualarm_qp.step.state import DualArmState

pytestmark = pytest.mark.skipif(example_robots_dir() is None,
                                reason="example-robot-data is not installed")

CONFIG = Path(__file__).resolve().parents[2] / "configs" / "ur5_pair_heavy_bar.yaml"


def _experiment(duration: float = 0.3, shoulder: float | None = None):
    data = yaml.safe_load(CONFIG.read_text())
    data["controller"]["duration"] = duration
    data["controller"].pop("torque_approach")  # the rows as they bind
    if shoulder is not None:
        data["follower"]["tau_max"][1] = shoulder
    return build_experiment(parse_config(data, CONFIG.name), CONFIG.name)


class DriftingPlant:
    """Moves as commanded, plus a drift of the follower's shoulder [rad per sample]."""

    def __init__(self, drift: float) -> None:
        self.drift = drift

    def reset(self, state, dt):
        pass

    def advance(self, state, command, dt):
        q_f = state.q_f + dt * command.qf_dot
        q_f[1] += self.drift
        return DualArmState(state.t + dt * command.scale, state.q_l + dt * command.ql_dot,
                            q_f, state.sigma + dt * command.m, state.sigma_leader)


def _shoulder_torques(result) -> np.ndarray:
    return np.abs(result.trace.tau_follower[:, 1])


def test_a_torque_beyond_the_limit_at_measured_states_is_a_warning_with_a_plant():
    exp = _experiment()
    free = rollout(exp.controller(), exp.initial, duration=exp.duration, limits=exp.limits)
    assert free.completed, free.failure
    # A limit just above what the plan needs: the drifting plant's states go beyond it
    # (a shoulder drift of 1 mrad per sample, 0.8 mm off closure: 0.14% beyond).
    limit = float(_shoulder_torques(free).max()) * 1.002
    exp = _experiment(shoulder=limit)
    drift = DriftingPlant(1e-3)
    result = rollout(exp.controller(), exp.initial, duration=exp.duration, limits=exp.limits,
                     plant=drift)
    assert _shoulder_torques(result).max() > limit * (1 + result.torque.allowance_rtol)
    assert result.failure is None or result.failure.criterion != "torque", result.failure
    assert any("needs" in w and "qf2" in w for w in result.warnings), result.warnings
    # The same recorded states without a plant are the run's own: they fail it.
    report = result.torque
    assert report is not None and not report.kept
    failure = torque_failure(report, result.trace)
    assert failure.criterion == "torque" and failure.limit == pytest.approx(limit)
    assert f"{limit:.4g} N m" in failure.message


def test_samples_without_torques_are_not_kept_and_fail_the_run_there():
    exp = _experiment(duration=0.1)
    result = rollout(exp.controller(), exp.initial, duration=exp.duration, limits=exp.limits)
    report = result.torque
    assert report is not None and report.kept
    unknown = dataclasses.replace(report, unbalanced=2, first_unbalanced=3)
    assert not unknown.kept
    failure = torque_failure(unknown, result.trace)
    assert failure.sample == 3 and failure.criterion == "torque"
    assert "cannot hold the load" in failure.message
