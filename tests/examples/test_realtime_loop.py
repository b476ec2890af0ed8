"""The 1 kHz loop example: its report adds up, and the rates it integrated keep the limits.

One second of ticks. Speed is never asserted: how many ticks miss depends on the
machine; only the counts' consistency and the commands are checked.
"""

from __future__ import annotations

import re
import runpy
from pathlib import Path

import numpy as np
import pytest

from dualarm_qp.kinematics.robots import example_robots_dir

ROOT = Path(__file__).resolve().parents[2]

pytestmark = pytest.mark.skipif(example_robots_dir() is None,
                                reason="needs the robots extra (example-robot-data)")


@pytest.fixture(scope="module")
def loop():
    example = runpy.run_path(str(ROOT / "examples" / "realtime_loop.py"))
    return example, example["run"](1.0)


def test_the_counts_add_up(loop):
    example, report = loop
    assert report.ticks == 1000
    assert report.ran[0]  # the first tick always gets its step
    assert report.steps == len(report.step_time) == len(report.finish) >= 1
    skipped = report.ticks - report.steps
    assert report.misses == int((report.finish > example["PERIOD"]).sum()) + skipped
    assert 0 <= report.misses <= report.ticks
    # A tick is skipped only when the step before it ran past that tick's start.
    late_any = report.finish > example["PERIOD"]
    assert skipped == 0 or late_any.any()
    assert (report.step_time > 0).all() and (report.late_start >= 0).all()
    # The step's own split is part of the wall time measured around it.
    assert (report.split.sum(axis=1) <= report.step_time + 1e-6).all()
    assert report.wall >= report.ticks * example["PERIOD"] * (1 - 1e-3)


def test_the_printed_report_is_the_measured_one(loop):
    example, report = loop
    text = example["summary"](report)
    assert f"ticks: {report.ticks} ({report.steps} steps" in text
    misses = re.search(r"^misses: (\d+) \((\d+) late steps \+ (\d+) skipped ticks\)$", text,
                       re.MULTILINE)
    assert misses is not None, text
    late, skipped = int(misses.group(2)), int(misses.group(3))
    assert int(misses.group(1)) == late + skipped == report.misses
    rate = re.search(r"^miss rate: ([\d.]+)%$", text, re.MULTILINE)
    assert rate is not None, text
    assert float(rate.group(1)) == pytest.approx(100 * report.misses / report.ticks, abs=1e-3)
    median = re.search(r"step time: median (\d+) us", text)
    assert median is not None
    assert float(median.group(1)) == pytest.approx(np.median(report.step_time) * 1e6, abs=0.5)
    assert text.splitlines()[-1].startswith("why: ")


def test_the_integrated_rates_keep_the_speed_limits(loop):
    example, report = loop
    exp = example["experiment"]()
    layout = exp.controller().layout
    assert report.names == tuple(layout.names)
    x = report.rates
    assert x.shape == (report.ticks, layout.n) and np.isfinite(x).all()
    assert np.abs(x).max() > 0  # the arms moved
    tol = 1e-9
    assert (np.abs(x[:, layout.leader]) <= exp.task.leader.qd_max * (1 + tol)).all()
    assert (np.abs(x[:, layout.follower]) <= exp.task.follower.qd_max * (1 + tol)).all()
    assert (np.abs(x[:, layout.grasps]) <= exp.options.grasp_speed_max * (1 + tol)).all()


def test_the_loop_sleeps_between_ticks_only_when_asked(monkeypatch):
    example = runpy.run_path(str(ROOT / "examples" / "realtime_loop.py"))
    time_module = example["time"]
    naps: list[float] = []
    real_sleep = time_module.sleep

    def counting_sleep(seconds: float) -> None:
        naps.append(seconds)
        real_sleep(seconds)

    monkeypatch.setattr(time_module, "sleep", counting_sleep)
    spin = example["run"](0.2)
    assert spin.wait == "spin" and spin.ticks == 200 and naps == []
    report = example["run"](0.2, wait="sleep")
    assert report.wait == "sleep" and report.ticks == 200 and report.steps >= 1
    assert naps and all(0.0 < t < example["PERIOD"] for t in naps)
    assert "waiting by sleep" in example["summary"](report)
    with pytest.raises(ValueError, match="spin, sleep"):
        example["run"](0.2, wait="nap")
    with pytest.raises(SystemExit) as exit_info:  # the command line refuses it too
        example["main"](["--wait", "nap", "--seconds", "0.1"])
    assert exit_info.value.code == 2
