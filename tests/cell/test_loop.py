"""The drive loop on a cell that follows the commands exactly: completion and every stop."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from fake import KinematicCell

from dualarm_qp.cell.loop import DriveSettings, drive
from dualarm_qp.cell.safety import command_limits
from dualarm_qp.experiments.config import load_config
from dualarm_qp.experiments.setup import build_experiment

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "configs" / "puma_beam_accel.yaml"


@pytest.fixture(scope="module")
def exp():
    e = build_experiment(load_config(CONFIG), str(CONFIG))
    return dataclasses.replace(e, duration=1.0)


def _drive(exp, cell, watchdog=3.0, **settings):
    s = DriveSettings(watchdog=watchdog * exp.options.dt, **settings)
    return drive(cell, exp.controller(), exp.initial, duration=exp.duration, settings=s,
                 limits=exp.limits)


def _cell(exp, **kw):
    return KinematicCell(exp.initial.q_l, exp.initial.q_f, exp.options.dt, **kw)


def _sent_within_limits(exp, res):
    lim = command_limits(exp.controller())
    sent = np.column_stack([v for k, v in res.columns.items() if "_sent" in k])
    v = np.vstack([np.zeros(lim.n), sent])
    acc = np.abs(np.diff(v, axis=0)) / lim.dt
    assert np.all(acc <= lim.a_max * (1 + 1e-9))
    assert np.all(np.abs(sent) <= lim.v_max * (1 + 1e-12))
    assert not np.any(sent[-1])  # at rest
    return sent


def test_a_cell_that_follows_exactly_completes_the_path(exp) -> None:
    cell = _cell(exp)
    res = _drive(exp, cell)
    assert res.result.completed, res.result.message
    assert res.result.path_completed == pytest.approx(1.0)
    tr = res.result.trace
    assert np.nanmax(tr.closure_pos_err) < 1e-4  # the estimated grasp closes
    _sent_within_limits(exp, res)
    assert cell.closed
    # what was sent is what the cell received, row for row, one command per sample on
    # the cell's clock (the row at the path's end carries the stop's first command)
    sent = np.column_stack([v for k, v in res.columns.items() if "_sent" in k])
    assert np.array_equal(np.array(cell.sends), sent)
    _on_the_grid(exp, cell)


def _on_the_grid(exp, cell):
    """Command k went out at the cell's time k dt: one per sample, the stop's too."""
    dt = exp.options.dt
    assert np.allclose(cell.send_times, dt * np.arange(len(cell.sends)), atol=1e-9)


def test_a_stale_state_stops_the_cell_and_the_arms_come_to_rest(exp) -> None:
    cell = _cell(exp, freeze_after=15)
    res = _drive(exp, cell, watchdog=1.5)  # before the tracking error passes its tolerance
    f = res.result.failure
    assert f is not None and f.criterion == "watchdog", res.result.message
    assert res.cell["stop"]["reason"] == "watchdog"
    sent = _sent_within_limits(exp, res)
    assert np.any(sent[res.cell["control_samples"] - 1])  # it was moving when it stopped
    assert res.cell["stop"]["samples"] > 1
    assert res.result.trace.status[-1] == "stopping"
    assert len(res.result.trace) == len(res.columns["robot_t"])
    _on_the_grid(exp, cell)
    # the states read again (one stamp) are measured once: no 0/0 in the realised limits
    for report in res.result.realised.values():
        assert np.isfinite(report.speed_ratio)


def test_an_interrupt_stops_the_cell_and_keeps_the_record(exp) -> None:
    cell = _cell(exp, interrupt_at=30)
    res = _drive(exp, cell)
    assert res.result.failure is not None and res.result.failure.criterion == "interrupted"
    assert res.cell["control_samples"] == 30
    _sent_within_limits(exp, res)
    _on_the_grid(exp, cell)


def test_a_lost_connection_stops_the_cell(exp) -> None:
    cell = _cell(exp, fail_at=25)
    res = _drive(exp, cell)
    assert res.result.failure.criterion == "cell"
    assert "connection" in res.result.message


def test_a_dry_run_sends_nothing_and_plans_the_whole_path(exp) -> None:
    cell = _cell(exp)
    res = _drive(exp, cell, dry_run=True)
    assert cell.sends == []
    assert res.result.completed, res.result.message
    assert "measured_offset" in res.columns
    assert np.nanmax(res.columns["measured_offset"]) > 0.0  # the robots stayed put


def test_robots_away_from_the_start_are_refused_before_anything_is_sent(exp) -> None:
    cell = _cell(exp, offset=0.05)
    res = _drive(exp, cell)
    assert res.result.failure.criterion == "start"
    assert cell.sends == []
    assert len(res.result.trace) == 0


def _jerk_within(lim, sent, rows):
    """The sent commands' third differences (from rest) within the jerk limits."""
    v = np.vstack([np.zeros((2, lim.n)), sent])
    jerk = np.abs(np.diff(v, n=2, axis=0))[rows] / lim.dt**2
    assert np.all(jerk <= lim.j_max * (1 + 1e-9)), np.max(jerk / lim.j_max)


@pytest.mark.parametrize("when", [40, 120])
def test_a_stop_keeps_the_jerk_limits_from_the_last_commands(when) -> None:
    pytest.importorskip("franky_sim")  # the FR3's description
    config = ROOT / "configs" / "fr3_pair.yaml"
    exp = build_experiment(load_config(config), str(config))
    cell = _cell(exp, interrupt_at=when)
    res = _drive(exp, cell)
    assert res.result.failure.criterion == "interrupted"
    sent = _sent_within_limits(exp, res)
    first = res.cell["control_samples"]
    assert np.any(sent[first - 1])  # moving when it stopped
    lim = command_limits(exp.controller())
    _jerk_within(lim, sent, slice(first - 2, None))  # the stop's, and the two before
    assert res.cell["stop"]["jerk_ratio_max"] <= 1 + 1e-9
    assert res.cell["stop"]["acceleration_ratio_max"] <= 1 + 1e-9
    _on_the_grid(exp, cell)
