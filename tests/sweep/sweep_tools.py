"""Helpers of the sweep tests: small sweep files and a real Dask cluster on loopback."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[2]
BASE = ROOT / "configs" / "puma_beam_limits.yaml"
BIN = Path(sys.executable).parent

#: The follower's start: the joints nearest the paper's Table 2 ones that close the grasp.
NEAR = [-164.1774, 32.065, -30.9446, 0, -1.1204, -105.8256]


def write_sweep(folder: Path, name: str = "small", *, duration: float = 0.5,
                grid: dict | None = None, extra: dict | None = None) -> Path:
    """A small sweep of the follower's base over the PUMA beam task (short runs)."""
    doc = {
        "name": name,
        "base": str(BASE),
        "set": {"controller.duration": duration,
                "follower.base": {"position": [300, 1380, 0]},
                "follower.initial": {"near": NEAR}},
        "grid": grid if grid is not None else {
            "follower.base.position.0": [0, 300, 600],
            "follower.base.position.1": [1000, 1380],
        },
    }
    doc.update(extra or {})
    path = folder / f"{name}.yaml"
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    return path


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def stop(proc: subprocess.Popen, sig: int = signal.SIGTERM) -> None:
    """Stop a process started in its own session (and its children), by its pid."""
    if proc.poll() is None:
        try:
            os.killpg(proc.pid, sig)
        except ProcessLookupError:
            pass
    try:
        proc.wait(timeout=20)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait(timeout=20)


def start_worker(address: str) -> subprocess.Popen:
    return subprocess.Popen([str(BIN / "dask"), "worker", address, "--nthreads", "1",
                             "--no-dashboard", "--host", "127.0.0.1"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            start_new_session=True)


def wait_for_workers(address: str, n: int) -> None:
    from distributed import Client

    with Client(address, timeout=30, set_as_default=False) as client:
        client.wait_for_workers(n, timeout=60)


class Cluster:
    """A ``dask scheduler`` and ``dask worker`` processes on 127.0.0.1."""

    def __init__(self, workers: int = 2) -> None:
        self.port = free_port()
        self.address = f"tcp://127.0.0.1:{self.port}"
        self.scheduler = subprocess.Popen(
            [str(BIN / "dask"), "scheduler", "--host", "127.0.0.1", "--port",
             str(self.port), "--no-dashboard"],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
        self.workers = [start_worker(self.address) for _ in range(workers)]
        wait_for_workers(self.address, workers)

    def close(self) -> None:
        for w in self.workers:
            stop(w)
        stop(self.scheduler)


def sweep_cmd(*args: str) -> list[str]:
    return [sys.executable, "-m", "dualarm_qp.cli", "sweep", *args]


def wait_for_lines(path: Path, n: int, proc: subprocess.Popen, timeout: float = 120) -> None:
    """Wait until the store ``path`` holds ``n`` lines (or the process ended)."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if path.exists() and path.read_bytes().count(b"\n") >= n:
            return
        if proc.poll() is not None:
            return
        time.sleep(0.05)
    raise AssertionError(f"{path} did not reach {n} lines")
