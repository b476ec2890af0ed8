"""The 1 kHz loop example: its report adds up, and the rates it integrated keep the limits.

One second of ticks. Speed is never asserted: how many ticks miss depends on the
machine; only the counts' consistency and the commands are checked.
"""

from __future__ import annotations

import os
import re
import runpy
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import dualarm_qp as dq
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
    lines = text.splitlines()
    assert sum(line.startswith("why: ") for line in lines) == 1
    if report.steal is None:
        assert lines[-1].startswith("why: ")
    else:  # Linux: the host's steal time per core, from /proc/stat
        assert report.steal.ndim == 1 and len(report.steal) >= 1
        assert (report.steal >= 0).all()
        steal = re.fullmatch(r"steal: the host gave (\d+) ms .*\(per core: ([\d, ]+) ms; "
                             r"counted in 10 ms units\)", lines[-1])
        assert steal is not None, lines[-1]
        assert float(steal.group(1)) == pytest.approx(1e3 * report.steal.sum(), abs=0.5)
        assert [float(v) for v in steal.group(2).split(", ")] == pytest.approx(
            1e3 * report.steal, abs=0.5)


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


def _example_main(*args: str, fake: str = "") -> subprocess.CompletedProcess[str]:
    """Run the example's command line in a process of its own (it may go real-time).

    ``fake``: "" runs it as it is; "fifo" refuses the real-time priority and "mlock" the
    locked memory (with the core's pinning and, for "fifo", the locking faked to
    succeed, so that the refusal is the same whatever this machine allows).
    """
    fakes = {
        "": "",
        "fifo": ("os.sched_setaffinity = lambda pid, cores: None\n"
                 "ctypes.CDLL = lambda *a, **k: Libc(0)\n"
                 "def refused(*a):\n    raise PermissionError(1, 'Operation not permitted')\n"
                 "os.sched_setscheduler = refused\n"),
        "mlock": ("os.sched_setaffinity = lambda pid, cores: None\n"
                  "ctypes.CDLL = lambda *a, **k: Libc(12)\n"
                  "os.sched_setscheduler = None\n"),  # never reached
    }
    code = ("import ctypes, os, runpy, sys\n"
            "class Libc:\n"
            "    def __init__(self, errno):\n        self.errno = errno\n"
            "    def mlockall(self, flags):\n"
            "        ctypes.set_errno(self.errno)\n        return -1 if self.errno else 0\n"
            + fakes[fake]
            + f"ex = runpy.run_path({str(ROOT / 'examples' / 'realtime_loop.py')!r})\n"
            + f"sys.exit(ex['main']({list(args)!r}))\n")
    # The child imports the package this process imported (an installed or a source copy).
    package_root = str(Path(dq.__file__).resolve().parents[1])
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [package_root, *filter(None, [os.environ.get("PYTHONPATH")])])}
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120, check=False, env=env)


@pytest.mark.slow
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="real-time scheduling is Linux's")
def test_realtime_runs_the_loop_or_says_what_was_refused():
    done = _example_main("--realtime", "--seconds", "0.3")
    if done.returncode == 0:  # allowed here (root, or the rights)
        first = done.stdout.splitlines()[0]
        assert re.fullmatch(r"real time: pinned to core \d+, memory locked, SCHED_FIFO "
                            r"priority 40", first), done.stdout
        assert "ticks: 300 (" in done.stdout and "waiting by sleep" in done.stdout
    else:
        assert done.returncode == 1, done.stderr
        assert re.fullmatch(r"--realtime: refused: (the core|locking the memory|the "
                            r"real-time priority) .+\n", done.stderr), done.stderr


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="real-time scheduling is Linux's")
@pytest.mark.parametrize(("fake", "message"), [
    ("fifo", "--realtime: refused: the real-time priority (SCHED_FIFO 40): Operation not "
             "permitted (it needs CAP_SYS_NICE, or an rtprio limit of at least 40)\n"),
    ("mlock", "--realtime: refused: locking the memory (mlockall): Cannot allocate memory "
              "(it needs CAP_IPC_LOCK, or a locked-memory limit, ulimit -l, above the "
              "process's size)\n"),
])
@pytest.mark.slow
def test_a_refused_realtime_step_is_named_and_no_loop_runs(fake: str, message: str):
    refused = _example_main("--realtime", "--seconds", "0.3", fake=fake)
    assert refused.returncode == 1 and refused.stderr == message, refused.stderr
    assert refused.stdout == ""  # no loop ran, nothing was printed


def test_realtime_will_not_spin():
    refused = _example_main("--realtime", "--wait", "spin", "--seconds", "0.1")
    assert refused.returncode == 2, refused.stderr
    assert "--realtime waits by sleep" in refused.stderr and refused.stdout == ""
