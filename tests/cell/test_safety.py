"""The clamp and the stop ramp keep every joint's speed, acceleration and jerk limit."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dualarm_qp.cell.safety import CommandLimits, StopRamp

DT = 0.01


def _limits(jerk: bool) -> CommandLimits:
    n = 4
    return CommandLimits(np.full(n, 2.0), np.array([5.0, 2.0, 8.0, 3.0]),
                         np.array([200.0, 50.0, 400.0, 100.0]) if jerk else np.full(n, np.inf),
                         DT)


def _within(seq: np.ndarray, lim: CommandLimits, v_prev: np.ndarray, a_prev: np.ndarray) -> None:
    v = np.vstack([v_prev, seq])
    a = np.diff(v, axis=0) / DT
    assert np.all(np.abs(seq) <= lim.v_max * (1 + 1e-12))
    assert np.all(np.abs(a) <= lim.a_max * (1 + 1e-9))
    if np.isfinite(lim.j_max).all():
        j = np.diff(np.vstack([a_prev, a]), axis=0) / DT
        assert np.all(np.abs(j) <= lim.j_max * (1 + 1e-9))


@pytest.mark.parametrize("jerk", [False, True])
def test_clamp_keeps_the_box_whatever_was_asked(jerk: bool) -> None:
    lim = _limits(jerk)
    rng = np.random.default_rng(1)
    v2 = np.zeros(4)
    v1 = np.zeros(4)
    sent = []
    for _ in range(300):
        asked = rng.normal(0.0, 5.0, 4)  # far beyond every limit
        v = lim.clamp(asked, v1, v2)
        sent.append(v)
        v2, v1 = v1, v
    _within(np.array(sent), lim, np.zeros(4), np.zeros(4))


def test_clamp_leaves_a_command_within_the_limits_as_it_is() -> None:
    lim = _limits(True)
    v1 = np.array([0.1, -0.2, 0.3, 0.0])
    v2 = np.array([0.1, -0.2, 0.3, 0.0])
    asked = v1 + 1e-5
    assert np.array_equal(lim.clamp(asked, v1, v2), asked)


def test_clamp_gives_way_on_jerk_no_more_than_it_must() -> None:
    # At the speed limit while still accelerating at the full rate: the jerk box lies
    # wholly above the speed limit, so the jerk cannot be kept. The command stays at
    # the limit (the least change of acceleration), whatever was asked.
    lim = _limits(True)
    v1 = lim.v_max.copy()
    v2 = v1 - lim.a_max * DT
    assert np.all(2 * v1 - v2 - lim.j_max * DT * DT > lim.v_max)  # the boxes are apart
    for asked in (np.full(4, -10.0), np.zeros(4), v1 - 0.5 * lim.a_max * DT):
        assert np.array_equal(lim.clamp(asked, v1, v2), lim.v_max)
    # and parted by rounding only (the boxes touch): the touching point
    v1 = lim.v_max - lim.a_max * DT / 4  # a quarter of an acceleration step below
    v2 = 2 * v1 - lim.j_max * DT * DT - lim.v_max
    for _ in range(100):
        apart = 2 * v1 - v2 - lim.j_max * DT * DT > lim.v_max
        if apart.all():
            break
        v2 = np.where(apart, v2, np.nextafter(v2, -np.inf))
    assert apart.all()
    out = lim.clamp(np.zeros(4), v1, v2)
    assert np.allclose(out, lim.v_max, rtol=0, atol=1e-12)


def _stop(lim: CommandLimits, v1: np.ndarray, v2: np.ndarray) -> np.ndarray:
    ramp = StopRamp(lim, v1, v2)
    out = []
    while not ramp.at_rest:
        out.append(ramp.next())
    return np.array(out)


@pytest.mark.parametrize("jerk", [False, True])
def test_stop_brings_every_joint_to_rest_within_its_limits(jerk: bool) -> None:
    lim = _limits(jerk)
    rng = np.random.default_rng(7)
    for _ in range(30):
        # a state reached within the limits: two clamped commands
        v2 = lim.clamp(rng.uniform(-2, 2, 4), np.zeros(4), np.zeros(4))
        for _ in range(40):
            v2 = lim.clamp(rng.uniform(-2, 2, 4), v2, v2)
        v1 = lim.clamp(rng.uniform(-2, 2, 4), v2, v2)
        seq = _stop(lim, v1, v2)
        assert np.all(seq[-1] == 0.0)
        _within(seq, lim, v1, (v1 - v2) / DT)


def test_stop_keeps_the_direction_and_is_as_short_as_the_acceleration_allows() -> None:
    lim = _limits(False)
    v = np.array([1.0, -0.5, 0.2, 0.0])
    seq = _stop(lim, v, v)
    # joint 2 (0.5 rad/s at 2 rad/s^2) needs the most samples: 0.5 / (2 * 0.01) = 25
    assert len(seq) == math.ceil(0.5 / (2.0 * DT))
    ratios = seq[:, :3] / v[:3]
    assert np.allclose(ratios, ratios[:, :1], atol=1e-12)  # one common factor
    assert np.all(seq[:, 3] == 0.0)


def test_a_pair_at_rest_needs_no_stop() -> None:
    lim = _limits(True)
    assert StopRamp(lim, np.zeros(4), np.zeros(4)).at_rest
