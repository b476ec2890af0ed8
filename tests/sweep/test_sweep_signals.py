"""A stop signal while the embedded cluster starts or closes: held, then a prompt, clean stop."""

from __future__ import annotations

import os
import signal
import subprocess
import time

import distributed
import psutil
import pytest
from sigint import child_default_sigint
from sweep_tools import stop, sweep_cmd, wait_for_lines, write_sweep

from dualarm_qp._signals import InterruptHandlers
from dualarm_qp.sweep import cluster


class _Fake:
    """A cluster or client that records what happened to it, and may signal on the way."""

    def __init__(self, log: list[str], name: str, signal_in: str = "") -> None:
        self.log, self.name, self.signal_in = log, name, signal_in
        self._step("start")

    def _step(self, what: str) -> None:
        if self.signal_in == what:
            signal.raise_signal(signal.SIGTERM)  # SIGINT may be ignored in a background run
        self.log.append(f"{self.name} {what}")

    def close(self, timeout: float) -> None:
        self._step("close")


def _open(monkeypatch: pytest.MonkeyPatch, signal_in: dict[str, str]) -> list[str]:
    log: list[str] = []
    monkeypatch.setattr(cluster, "_local_cluster",
                        lambda n: _Fake(log, "cluster", signal_in.get("cluster", "")))
    monkeypatch.setattr(distributed, "Client",
                        lambda c, **kw: _Fake(log, "client", signal_in.get("client", "")))
    with InterruptHandlers(), pytest.raises(KeyboardInterrupt):
        with cluster.open_client(workers=1):
            log.append("sweep")
        log.append("not interrupted")
    return log


def test_a_signal_while_the_cluster_starts_stops_the_sweep_once_it_is_up_and_closed(
        monkeypatch):
    log = _open(monkeypatch, {"cluster": "start"})
    assert log == ["cluster start", "client start", "client close", "cluster close"]


def test_a_signal_while_the_cluster_closes_stops_the_sweep_once_all_is_closed(monkeypatch):
    log = _open(monkeypatch, {"client": "close"})
    assert log == ["cluster start", "client start", "sweep", "client close", "cluster close"]


def _interrupt_when(sweep_args: list[str], ready, timeout: float = 180):
    """Run a sweep, send it SIGINT once ``ready(proc)``; return (code, stderr, s to exit)."""
    proc = subprocess.Popen(sweep_cmd(*sweep_args), stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, preexec_fn=child_default_sigint)
    try:
        end = time.monotonic() + timeout
        while not ready(proc) and proc.poll() is None and time.monotonic() < end:
            time.sleep(0.02)
        assert proc.poll() is None, "the sweep ended before the signal"
        os.kill(proc.pid, signal.SIGINT)
        sent = time.monotonic()
        _, err = proc.communicate(timeout=60)
        return proc.returncode, err, time.monotonic() - sent
    finally:
        stop(proc)


@pytest.mark.slow
@pytest.mark.sigint
def test_sigint_while_the_local_cluster_starts_exits_130_without_a_traceback(tmp_path):
    sweep = write_sweep(tmp_path)

    def starting(proc):  # the first worker process is there: the cluster is starting
        try:
            return bool(psutil.Process(proc.pid).children())
        except psutil.NoSuchProcess:
            return False

    code, err, took = _interrupt_when([str(sweep), "--out", str(tmp_path / "out"),
                                       "--workers", "1", "--quiet"], starting)
    assert code == 130, err
    assert "Traceback" not in err and "Exception ignored" not in err, err
    assert err.strip().splitlines()[-1].startswith("dualarm-qp: error: interrupted (SIGINT)")
    assert took < 8, took


@pytest.mark.slow
@pytest.mark.sigint
def test_sigint_after_the_last_point_exits_promptly(tmp_path):
    sweep = write_sweep(tmp_path, grid={"follower.base.position.0": [300, 350]})
    out = tmp_path / "out"

    def all_stored(proc):
        wait_for_lines(out / "points.jsonl", 2, proc, timeout=180)
        return True

    code, err, took = _interrupt_when([str(sweep), "--out", str(out), "--workers", "1",
                                       "--quiet"], all_stored)
    assert code == 130, err
    assert "Traceback" not in err and "Exception ignored" not in err, err
    assert took < 6, took  # Dask's exit hook closing a half-closed cluster took 10 s
