"""The drive loop on a cell that follows the commands exactly: completion and every stop."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from fake import KinematicCell

from dualarm_qp.cell.loop import DriveSettings, command_limits, drive
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
    # what was sent is what the cell received, row for row (the row at the path's end
    # holds the command in force: the stop ramp's first command comes after it)
    sent = np.column_stack([v for k, v in res.columns.items() if "_sent" in k])
    end = res.cell["control_samples"] - 1
    assert np.array_equal(np.array(cell.sends), np.delete(sent, end, axis=0))


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


def test_an_interrupt_stops_the_cell_and_keeps_the_record(exp) -> None:
    cell = _cell(exp, interrupt_at=30)
    res = _drive(exp, cell)
    assert res.result.failure is not None and res.result.failure.criterion == "interrupted"
    assert res.cell["control_samples"] == 30
    _sent_within_limits(exp, res)


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
