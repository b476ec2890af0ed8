"""Two FR3 arms through libfranka's protocol: ``dualarm-qp drive configs/fr3_pair.yaml
--cell franka`` against ``dualarm-qp serve configs/fr3_pair.yaml --cell franka``
(franky-sim serving both arms on 127.0.0.1 and 127.0.0.2), judged from the folder's
files on the robots' own clock.

The simulator serves on fixed addresses: a lock file keeps two test workers (or two
test runs on one machine) from serving there at once.
"""

from __future__ import annotations

import fcntl
import os
import select
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pytest
from record_checks import check_motion, check_sent, check_task, read_record, sent_names
from sigint import child_default_sigint

pytest.importorskip("franky")
pytest.importorskip("franky_sim")

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "configs" / "fr3_pair.yaml"
CLI = [sys.executable, "-m", "dualarm_qp.cli"]


@contextmanager
def _addresses_to_ourselves() -> Iterator[None]:
    """Hold the loopback addresses' lock (a file in the temporary folder) in the block."""
    with open(Path(tempfile.gettempdir()) / "dualarm-qp-franka-loopback.lock", "w") as fh:
        fcntl.flock(fh, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(fh, fcntl.LOCK_UN)


@contextmanager
def served(config: Path) -> Iterator[subprocess.Popen[str]]:
    """``dualarm-qp serve config --cell franka`` in its own process group, until SIGTERM."""
    with _addresses_to_ourselves():
        with _serve(config) as proc:
            yield proc


@contextmanager
def _serve(config: Path) -> Iterator[subprocess.Popen[str]]:
    # At a tenth of the wall clock's pace: the drive (Python, one step per sample, beside
    # libfranka's 1 kHz threads) keeps the simulator's pace on two cores shared with the
    # other test workers (at a quarter, a wrist's recorded jerk went over its limit in 2
    # of 3 parallel runs: the drive had fallen behind the robots' clock, not the plan).
    proc = subprocess.Popen([*CLI, "serve", str(config), "--cell", "franka", "--pace", "0.1"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)
    try:
        line = ""
        deadline = time.monotonic() + 180
        while "serving" not in line:
            ready, _, _ = select.select([proc.stdout], [], [], 1.0)
            if ready:
                line = proc.stdout.readline()  # type: ignore[union-attr]
            assert proc.poll() is None, proc.stderr.read()  # type: ignore[union-attr]
            assert time.monotonic() < deadline, "serve did not come up"
        assert "127.0.0.1, 127.0.0.2" in line, line
        yield proc
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGTERM)
        try:
            _, err = proc.communicate(timeout=60)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.communicate()
            raise
    assert proc.returncode == 130, err
    assert "stopped (SIGTERM)" in err and "Traceback" not in err, err
    print(err.strip().splitlines()[-1])  # the ticks without a command, if any


def _drive(out: Path, **popen) -> subprocess.Popen[str]:
    return subprocess.Popen([*CLI, "drive", str(CONFIG), "--cell", "franka", "--out", str(out),
                             "--no-plots"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, **popen)


def _clients_connected() -> int:
    """How many TCP connections to a Franka's port (1337) are established on this host."""
    try:
        lines = Path("/proc/net/tcp").read_text().splitlines()[1:]
    except OSError:  # not Linux: the caller waits on the wall clock only
        return 2
    return sum(1 for line in lines
               if line.split()[2].endswith(":0539") and line.split()[3] == "01")


def _under_way(out: Path, proc: subprocess.Popen[str], seconds: float) -> None:
    """Wait until the drive has connected to both arms (its loop starts then), then
    ``seconds`` of wall time: the simulator serves 0.1 to 0.5 s of the robots' time per
    second here."""
    deadline = time.monotonic() + 120
    while not out.exists() or _clients_connected() < 2:
        assert proc.poll() is None and time.monotonic() < deadline
        time.sleep(0.01)
    time.sleep(seconds)
    assert proc.poll() is None


def test_two_fr3_arms_through_libfrankas_protocol(tmp_path: Path) -> None:
    with served(CONFIG):
        # the addresses are taken: a second simulator refuses them (bad input)
        second = subprocess.run([*CLI, "serve", str(CONFIG), "--cell", "franka"],
                                capture_output=True, text=True, timeout=120)
        assert second.returncode == 2 and "127.0.0.1" in second.stderr, second.stderr
        out = tmp_path / "drive"
        proc = _drive(out)
        _, stderr = proc.communicate(timeout=900)
        assert proc.returncode == 0, stderr
    rec = read_record(out)
    s = rec.summary
    assert s["status"] == "completed" and s["path_completed_pct"] == 100.0, s["message"]
    assert s["cell"]["kind"] == "franka" and s["cell"]["stop"]["at_rest"]
    # on the robots' clock: one sample per dt (a late tick shows, and is measured so)
    dt = s["dt_s"]
    ticks = np.diff(rec.col("robot_t")) / dt
    assert np.all(np.abs(ticks - 1) <= 0.1 + 1e-9), ticks
    ratios = check_motion(rec, CONFIG)  # every limit kept, the stop's rows too
    check_sent(rec, CONFIG)
    closure, tracking = check_task(rec, CONFIG)
    assert closure < 1e-3 and tracking < 2e-3
    print(f"limits used {ratios}; closure {closure * 1e3:.3f} mm, object off its path "
          f"{tracking * 1e3:.3f} mm; {s['samples']} samples in {s['wall_time_s']:.1f} s")


def test_a_drive_killed_or_cut_off_leaves_a_whole_record(tmp_path: Path) -> None:
    # SIGTERM in the middle of the path: exit 130, the arms brought to rest within the
    # limits, every sample recorded
    with served(CONFIG):
        out = tmp_path / "term"
        proc = _drive(out, preexec_fn=child_default_sigint)
        _under_way(out, proc, 2.0)
        proc.send_signal(signal.SIGTERM)
        _, stderr = proc.communicate(timeout=300)
    assert proc.returncode == 130, stderr
    assert "Traceback" not in stderr
    rec = read_record(out)
    s = rec.summary
    assert s["status"] == "interrupted" and "SIGTERM" in s["message"]
    assert 0 < s["path_completed_pct"] < 100
    assert s["cell"]["stop"]["at_rest"] and s["cell"]["stop"]["samples"] > 1
    assert np.any(rec.cols(sent_names(), rec.control)[-1])  # moving when it was stopped
    check_motion(rec, CONFIG)
    check_sent(rec, CONFIG)
    # a cell that stops answering (its simulator frozen): exit 1, the record whole
    with served(CONFIG) as server:
        out = tmp_path / "frozen"
        proc = _drive(out)
        _under_way(out, proc, 1.5)
        os.killpg(server.pid, signal.SIGSTOP)
        try:
            _, stderr = proc.communicate(timeout=120)
        finally:
            os.killpg(server.pid, signal.SIGCONT)
    assert proc.returncode == 1, stderr
    rec = read_record(out)
    s = rec.summary
    assert s["status"] == "failed" and s["failure"]["criterion"] == "cell", s["message"]
    assert "Franka" in s["message"]
    check_motion(rec, CONFIG, rec.control)
