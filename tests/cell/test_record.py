"""A cell's record measured on the cell's own clock, and the stop's summary."""

from __future__ import annotations

import numpy as np
import pytest

from dualarm_qp.cell.record import stop_summary
from dualarm_qp.cell.safety import CommandLimits
from dualarm_qp.control.realised import measure

DT = 0.01


def _measure(x, times, a=1.0, j=1.0):
    n = x.shape[1]
    return measure(x, np.full(n, -np.inf), np.full(n, np.inf), np.full(n, 10.0), times,
                   [f"x{i}" for i in range(n)], a_max=np.full(n, a),
                   acceleration_rule=True, j_max=np.full(n, j), jerk_rule=True)


def test_a_late_tick_is_measured_on_the_cells_clock() -> None:
    # constant speed 0.3 per s; sample 5 read a millisecond late, as a robot's clock says
    times = DT * np.arange(10)
    times[5] += 0.001
    x = 0.3 * times[:, None]
    x[0] = 0.0
    rep = _measure(x, times, a=1e9, j=1e9)
    assert rep.speed_ratio == pytest.approx(0.03, rel=1e-9)
    # on the nominal grid the late sample reads as a jump of 30 per s^2
    assert _measure(x, DT, a=1e9, j=1e9).acceleration_ratio > 20 / 1e9


def test_a_constant_jerk_at_uneven_times_is_measured_as_one() -> None:
    # x = t^3 from rest: jerk 6 throughout; ticks up to a millisecond early or late
    rng = np.random.default_rng(3)
    times = np.cumsum(np.r_[0.0, DT + rng.uniform(-0.001, 0.001, 40)])
    x = (times**3)[:, None]
    assert _measure(x, times, a=1e9, j=6.0).jerk_ratio == pytest.approx(1.0, abs=0.15)
    assert _measure(x, DT, a=1e9, j=6.0).jerk_ratio > 50  # the nominal grid: noise


def test_the_stop_summary_counts_from_the_stops_first_command() -> None:
    lim = CommandLimits(np.full(2, 1.0), np.full(2, 2.0), np.full(2, 100.0), DT)
    # two control commands accelerating at 2, then a stop of three commands
    sent = [np.array([0.02, 0.0]), np.array([0.04, 0.0]), np.array([0.05, 0.0]),
            np.array([0.04, 0.0]), np.array([0.0, 0.0])]
    out = stop_summary(lim, sent, 2, "interrupted")
    assert out["samples"] == 3 and out["at_rest"]
    assert out["acceleration_ratio_max"] == pytest.approx(2.0)  # 0.04 -> 0 in one sample
    # jerks: (0.05 - 0.04) - (0.04 - 0.02) = -0.01, ... , (0 - 0.04) - (0.04 - 0.05) = -0.03
    assert out["jerk_ratio_max"] == pytest.approx(0.03 / DT**2 / 100.0)
