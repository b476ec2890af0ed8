"""Sweep throughput: points per second with 1 and 2 local workers, and on a real cluster.

Runs the bundled follower base map (configs/sweeps/follower_base_map.yaml) three times
into fresh folders: an embedded LocalCluster with 1 worker, with 2 workers, and through a
`dask scheduler` plus two `dask worker` processes started here on 127.0.0.1. For each it
reports the points per second (points run / wall time of the whole command, cluster
start included), the mean run time of a point (as measured inside the worker) and the
scheduling overhead per point: (workers x wall time - sum of point run times) / points.

    .venv/bin/python benchmarks/sweep_throughput.py [--sweep FILE]
"""

from __future__ import annotations

import argparse
import os
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pyarrow.parquet as pq

ROOT = Path(__file__).resolve().parents[1]
BIN = Path(sys.executable).parent


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _sweep(sweep: Path, out: Path, *where: str) -> float:
    t0 = time.perf_counter()
    subprocess.run([str(BIN / "dualarm-qp"), "sweep", str(sweep), "--out", str(out),
                    "--quiet", *where], check=True, stdout=subprocess.DEVNULL)
    return time.perf_counter() - t0


def _row(label: str, workers: int, wall: float, out: Path) -> dict[str, float | str]:
    rows = pq.read_table(out / "results.parquet").to_pylist()
    run = [r["wall_time_s"] for r in rows if r["criterion"] != "start_unreachable"]
    busy = sum(run)
    return {"label": label, "points": len(rows), "wall_s": wall, "points_per_s": len(rows) / wall,
            "point_run_s": busy / len(run), "overhead_per_point_s":
            (workers * wall - busy) / len(rows)}


def _stop(proc: subprocess.Popen) -> None:
    if proc.poll() is None:
        os.killpg(proc.pid, signal.SIGTERM)
    proc.wait(timeout=30)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sweep", type=Path,
                    default=ROOT / "configs" / "sweeps" / "follower_base_map.yaml")
    args = ap.parse_args()
    results = []
    with tempfile.TemporaryDirectory() as tmp:
        for n in (1, 2):
            out = Path(tmp) / f"local{n}"
            results.append(_row(f"LocalCluster, {n} worker{'s' * (n > 1)}", n,
                                _sweep(args.sweep, out, "--workers", str(n)), out))
        port = _free_port()
        address = f"tcp://127.0.0.1:{port}"
        procs = [subprocess.Popen([str(BIN / "dask"), "scheduler", "--host", "127.0.0.1",
                                   "--port", str(port), "--no-dashboard"],
                                  stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                  start_new_session=True)]
        try:
            time.sleep(2)
            procs += [subprocess.Popen([str(BIN / "dask"), "worker", address, "--nthreads", "1",
                                        "--no-dashboard"], stdout=subprocess.DEVNULL,
                                       stderr=subprocess.DEVNULL, start_new_session=True)
                      for _ in range(2)]
            from distributed import Client

            with Client(address, timeout=30, set_as_default=False) as client:
                client.wait_for_workers(2, timeout=60)
            out = Path(tmp) / "external"
            results.append(_row("dask scheduler + 2 dask worker", 2,
                                _sweep(args.sweep, out, "--scheduler", address), out))
        finally:
            for p in reversed(procs):
                _stop(p)
    name = args.sweep.relative_to(ROOT) if args.sweep.is_relative_to(ROOT) else args.sweep
    print(f"sweep: {name}, {os.cpu_count()} cores, Python {sys.version.split()[0]}")
    print("| run | points | wall [s] | points/s | point run [s] | overhead/point [s] |")
    print("|---|---|---|---|---|---|")
    for r in results:
        print(f"| {r['label']} | {r['points']} | {r['wall_s']:.1f} | {r['points_per_s']:.2f} "
              f"| {r['point_run_s']:.3f} | {r['overhead_per_point_s']:.3f} |")
    print(f"speed-up of 2 local workers over 1: "
          f"{results[1]['points_per_s'] / results[0]['points_per_s']:.2f}x")


if __name__ == "__main__":
    main()
