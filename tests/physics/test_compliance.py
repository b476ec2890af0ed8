"""The compliant follower's rows: the closure, with admittance where the grasp holds."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from dualarm_qp.control.measured import HandReading
from dualarm_qp.control.rollout import rollout
from dualarm_qp.errors import InvalidInputError
from dualarm_qp.experiments import build_experiment, load_config
from dualarm_qp.physics.compliance import (
    ComplianceGains,
    ComplianceTask,
    NoWrenchReadingError,
    WrenchMeasurement,
)
from dualarm_qp.step.build import StepBuilder
from dualarm_qp.step.state import DualArmState
from dualarm_qp.task.hands import hand_statics
from dualarm_qp.task.loads import ObjectLoad, split_load

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
BEAM = CONFIGS / "puma_beam_limits.yaml"
SUPPORT = CONFIGS / "puma_beam_support.yaml"
GAINS = ComplianceGains(force_gain=1e-3, moment_gain=1e-2, filter_time=0.0)
LOAD = ObjectLoad(3.0, np.array([0.0, 0.0, 0.25]), np.array([0.0, 0.0, -9.81]))


def _experiment(path: Path):
    return build_experiment(load_config(path), str(path))


def _reading(leader: np.ndarray, follower: np.ndarray) -> HandReading:
    return HandReading(leader, follower, 0.0, np.zeros(6), 0.5, np.zeros(7))


def _closure_rows(exp, state: DualArmState, task: ComplianceTask | None):
    builder = StepBuilder(exp.task, exp.options, tasks=() if task is None else (task,))
    problem = builder.build(state).problem
    return np.asarray(problem.A)[6:12], np.asarray(problem.b)[6:12], builder


def _off_closure(exp) -> DualArmState:
    """The start, with the follower's joints a little off the grasp (a closure error)."""
    s = exp.initial
    return dataclasses.replace(s, q_f=s.q_f + np.array([2e-3, -1e-3, 1.5e-3, 0, 1e-3, 0]))


def _plan(task, state: DualArmState, load: ObjectLoad) -> tuple[np.ndarray, np.ndarray]:
    hands, T = hand_statics(dataclasses.replace(task, load=load), state.q_l, state.sigma,
                            state.sigma_leader)
    w = split_load(hands, load, T).wrenches
    return w[0], w[1]


def test_the_compliant_closure_takes_the_standard_closures_place():
    exp = _experiment(BEAM)
    task = ComplianceTask(50.0, LOAD, GAINS)
    builder = StepBuilder(exp.task, exp.options, tasks=(task,))
    assert builder.tasks[1] is task and len(builder.tasks) == 2
    with pytest.raises(InvalidInputError, match="one grasp closure"):
        StepBuilder(exp.task, exp.options,
                    tasks=(task, ComplianceTask(50.0, LOAD, GAINS)))


def test_without_a_reading_it_refuses_to_step_and_says_what_it_needs():
    exp = _experiment(BEAM)
    task = ComplianceTask(float(exp.options.correction_gain), LOAD, GAINS)
    with_task = dataclasses.replace(exp, tasks_extra=(task,), duration=0.31)
    result = rollout(with_task.controller(), exp.initial, duration=0.31, limits=exp.limits)
    assert not result.completed and result.failure is not None
    assert "no reading of the hands' wrenches" in result.failure.message
    assert "plant that measures them" in result.failure.message
    with pytest.raises(NoWrenchReadingError):
        task.equality(None)  # type: ignore[arg-type]  # refused before the context is read


def test_at_the_planned_split_only_the_free_directions_keep_the_closure_feedback():
    """Measured = planned: no admittance, and the closure error's held part is not fed
    back (the hand cannot move there on the object: that error would become force)."""
    exp = _experiment(BEAM)
    state = _off_closure(exp)
    gain = float(exp.options.correction_gain)
    A0, b0, _ = _closure_rows(exp, state, None)
    task = ComplianceTask(gain, LOAD, GAINS)
    task.measurement.update(_reading(*_plan(exp.task, state, LOAD)), 0.031)
    A, b, _ = _closure_rows(exp, state, task)
    np.testing.assert_array_equal(A, A0)
    np.testing.assert_allclose(task.twist, 0.0, atol=1e-12)
    hands, _ = hand_statics(dataclasses.replace(exp.task, load=LOAD), state.q_l, state.sigma)
    s = hands[1].free[:3, 0]  # the slide: along the bar; the spin: about it
    free = np.zeros((6, 2))
    free[:3, 0], free[3:, 1] = s, s
    np.testing.assert_allclose(b, free @ (free.T @ b0), atol=1e-12)
    assert np.linalg.norm(b0 - b) > 0.1 * np.linalg.norm(b0)  # the held part was there


def test_a_follower_pushing_beyond_its_share_is_moved_back_along_the_push():
    """An internal push (the follower up, the leader down by as much, the weight still
    balanced) moves the follower's hand down at K_f per newton; a twist about the bar's
    normal, back at K_m per N m. A force along the bar is none the grasp can carry."""
    exp = _experiment(BEAM)
    state = exp.initial
    w_l, w_f = _plan(exp.task, state, LOAD)
    hands, _ = hand_statics(dataclasses.replace(exp.task, load=LOAD), state.q_l, state.sigma)
    s = hands[1].free[:3, 0]
    up = np.array([0.0, 0.0, 1.0])
    normal = np.cross(s, up)
    normal /= np.linalg.norm(normal)
    push, twist = 7.0 * up, 0.4 * normal  # [N], [N m]
    lever = hands[1].point - hands[0].point
    for along in (0.0, 5.0):  # a force along the bar the sliding grasp cannot carry
        w_f2 = w_f + np.r_[push + along * s, twist]
        w_l2 = w_l - np.r_[push + along * s, twist + np.cross(lever, push + along * s)]
        task = ComplianceTask(0.0, LOAD, GAINS)  # no closure feedback: the admittance alone
        task.measurement.update(_reading(w_l2, w_f2), 0.031)
        _, b, _ = _closure_rows(exp, state, task)
        expected = -np.r_[GAINS.force_gain * push, GAINS.moment_gain * twist]
        np.testing.assert_allclose(task.twist, expected, atol=1e-9)
        np.testing.assert_allclose(b, expected, atol=1e-9)


def test_a_support_regulates_its_normal_force_to_the_support_lines():
    exp = _experiment(SUPPORT)
    state = exp.initial
    load = exp.task.load
    assert load is not None
    w_l, w_f = _plan(exp.task, state, load)
    normal = w_f[:3] / np.linalg.norm(w_f[:3])
    task = ComplianceTask(0.0, load, GAINS)
    excess = 3.0  # N beyond the support line's push
    task.measurement.update(_reading(w_l - np.r_[excess * normal, np.zeros(3)],
                                     w_f + np.r_[excess * normal, np.zeros(3)]), 0.031)
    _closure_rows(exp, state, task)
    np.testing.assert_allclose(task.twist, np.r_[-GAINS.force_gain * excess * normal,
                                                 np.zeros(3)], atol=1e-12)


def test_the_measurement_filter_is_first_order():
    m = WrenchMeasurement(filter_time=0.1)
    zero, one = np.zeros(6), np.ones(6)
    m.update(_reading(zero, zero), 0.01)
    np.testing.assert_array_equal(m.follower, zero)  # the first reading as it is
    for _ in range(10):
        m.update(_reading(one, one), 0.01)
    assert m.follower is not None
    np.testing.assert_allclose(m.follower, 1.0 - np.exp(-10 * 0.01 / 0.1))
    m.reset()
    assert m.follower is None and m.updates == 0


@pytest.mark.parametrize("key", ["force_gain", "moment_gain", "filter_time"])
def test_gains_are_finite_and_not_negative(key):
    with pytest.raises(InvalidInputError, match=key):
        ComplianceGains(**{key: -1.0})
