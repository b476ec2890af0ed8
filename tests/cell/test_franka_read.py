"""The Franka cell's reading, without robots: both arms' joints at the sample's tick.

Each arm's state is polled until its clock reaches the sample; a poll that came late
keeps that arm's first state a tick (or more) past it. The reading then brings that
arm's joints back to the sample's tick with its measured rates, and says how late it
was (``Reading.late``): two arms' joints a millisecond apart, stamped alike, read as a
jerk many times the limit in the third differences of the record.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

from dualarm_qp.cell.franka import FrankaCell


@dataclass
class _Time:
    seconds: float

    def to_sec(self) -> float:
        return self.seconds


@dataclass
class _State:
    time: _Time
    q: np.ndarray
    dq: np.ndarray


class _Robot:
    """A robot whose state, read after read, is the next of ``ticks`` (then the last)."""

    def __init__(self, ticks: list[float], q0: float, speed: float) -> None:
        self.states = [_State(_Time(t), np.full(7, q0 + speed * t), np.full(7, speed))
                       for t in ticks]

    @property
    def state(self) -> _State:
        return self.states.pop(0) if len(self.states) > 1 else self.states[0]


def _cell(leader: _Robot, follower: _Robot) -> FrankaCell:
    zeros = np.zeros(7)
    cell = FrankaCell(("127.0.0.1", "127.0.0.2"), ((zeros, zeros, zeros),) * 2, hold=0.05)
    cell.robots = [leader, follower]
    cell._t0 = [0.0, 0.0]
    return cell


def test_a_state_kept_late_is_brought_back_to_the_samples_tick() -> None:
    # the leader is polled at its sample's tick (0.010 s); the follower's poll came a
    # tick late (0.011 s): its joints then are 0.5 rad/s x 1 ms further on
    leader = _Robot([0.009, 0.010], q0=0.1, speed=-0.2)
    follower = _Robot([0.009, 0.011], q0=0.3, speed=0.5)
    cell = _cell(leader, follower)
    cell.wait_until(0.010)
    reading = cell.read()
    assert reading.t == pytest.approx(0.010)
    assert reading.late == pytest.approx(0.001)
    np.testing.assert_allclose(reading.q_l, 0.1 - 0.2 * 0.010, rtol=0, atol=1e-15)
    np.testing.assert_allclose(reading.q_f, 0.3 + 0.5 * 0.010, rtol=0, atol=1e-15)


def test_both_arms_kept_late_are_brought_back_to_the_samples_tick() -> None:
    leader = _Robot([0.009, 0.011], q0=0.1, speed=-0.2)
    follower = _Robot([0.009, 0.012], q0=0.3, speed=0.5)
    cell = _cell(leader, follower)
    cell.wait_until(0.010)
    reading = cell.read()
    assert reading.t == pytest.approx(0.010) and reading.late == pytest.approx(0.002)
    np.testing.assert_allclose(reading.q_l, 0.1 - 0.2 * 0.010, rtol=0, atol=1e-15)
    np.testing.assert_allclose(reading.q_f, 0.3 + 0.5 * 0.010, rtol=0, atol=1e-15)


def test_states_at_the_samples_tick_are_read_as_they_are() -> None:
    cell = _cell(_Robot([0.020], q0=0.1, speed=0.3), _Robot([0.020], q0=0.2, speed=-0.4))
    cell.wait_until(0.020)
    reading = cell.read()
    assert reading.t == pytest.approx(0.020) and reading.late == 0.0
    np.testing.assert_array_equal(reading.q_l, np.full(7, 0.1 + 0.3 * 0.020))
    np.testing.assert_array_equal(reading.q_f, np.full(7, 0.2 - 0.4 * 0.020))
