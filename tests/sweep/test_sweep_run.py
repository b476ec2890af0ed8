"""Sweeps on a real Dask cluster: local or existing, faults, interrupts, resuming."""

from __future__ import annotations

import json
import math
import os
import signal
import subprocess

import pyarrow.parquet as pq
import pytest
from sigint import child_default_sigint
from sweep_tools import stop, sweep_cmd, wait_for_lines, write_sweep

from dualarm_qp.cli import main

#: Columns that depend on where and when a point ran, not on what it computed.
RUN_COLUMNS = {"wall_time_s", "worker", "step_time_median_s", "step_time_p99_s"}


def _rows(out):
    return pq.read_table(out / "results.parquet").to_pylist()


def _same(a, b):
    return a == b or (isinstance(a, float) and isinstance(b, float)
                      and math.isnan(a) and math.isnan(b))


def _comparable(rows):
    return [{k: v for k, v in r.items() if k not in RUN_COLUMNS} for r in rows]


def _store_keys(out):
    return [json.loads(line)["key"] for line in (out / "points.jsonl").read_text().splitlines()]


def test_local_cluster_and_external_cluster_give_the_same_rows(tmp_path, cluster, capsys):
    sweep = write_sweep(tmp_path)
    local, remote = tmp_path / "local", tmp_path / "remote"
    assert main(["sweep", str(sweep), "--out", str(local), "--workers", "2", "--quiet"]) == 0
    assert main(["sweep", str(sweep), "--out", str(remote), "--scheduler", cluster.address,
                 "--quiet"]) == 0
    a, b = _rows(local), _rows(remote)
    assert len(a) == 6 and [r["point"] for r in a] == list(range(6))
    for ra, rb in zip(_comparable(a), _comparable(b), strict=True):
        assert ra.keys() == rb.keys()
        assert all(_same(ra[k], rb[k]) for k in ra), (ra, rb)
    statuses = {(r["follower.base.position.0"], r["follower.base.position.1"]): r["status"]
                for r in a}
    assert statuses[(300, 1380)] == "completed"
    assert statuses[(0, 1000)] == "failed"
    assert {r["criterion"] for r in a if r["status"] == "failed"} >= {"start_unreachable"}
    ran_on = {r["worker"] for r in b if r["criterion"] != "start_unreachable"}
    assert ran_on <= set(cluster_workers(cluster)) and ran_on
    # The CSV holds the same points and columns.
    header, *lines = (remote / "results.csv").read_text().splitlines()
    assert header.split(",")[:3] == ["point", "follower.base.position.0",
                                     "follower.base.position.1"]
    assert len(lines) == 6
    html = (remote / "report.html").read_text()
    assert "data:image/png;base64," in html and "<script" not in html
    # Rerun: every point is stored, nothing is computed again.
    assert main(["sweep", str(sweep), "--out", str(remote), "--scheduler", cluster.address,
                 "--quiet"]) == 0
    assert "(0 computed now)" in capsys.readouterr().out
    assert len(_store_keys(remote)) == 6


def cluster_workers(cluster):
    from distributed import Client

    with Client(cluster.address, timeout=30, set_as_default=False) as client:
        return list(client.scheduler_info()["workers"])


def test_a_worker_killed_mid_sweep_loses_nothing(tmp_path, cluster):
    grid = {"follower.base.position.0": [100, 200, 300, 400],
            "follower.base.position.1": [1300, 1380, 1450]}
    sweep = write_sweep(tmp_path, grid=grid, duration=2.0)
    out = tmp_path / "out"
    proc = subprocess.Popen(sweep_cmd(str(sweep), "--out", str(out), "--scheduler",
                                      cluster.address, "--quiet", "--batch", "1"),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        wait_for_lines(out / "points.jsonl", 2, proc)
        assert proc.poll() is None, "the sweep ended before a worker could be killed"
        stop(cluster.workers[0], signal.SIGKILL)  # the worker and its process group
        _, err = proc.communicate(timeout=300)
    finally:
        stop(proc)
    assert proc.returncode == 0, err
    rows = _rows(out)
    assert len(rows) == 12 and all(r["status"] != "interrupted" for r in rows)
    keys = _store_keys(out)
    assert len(keys) == len(set(keys)) == 12  # every point stored once


@pytest.mark.sigint
def test_sigint_leaves_a_partial_table_and_the_sweep_resumes(tmp_path):
    grid = {"follower.base.position.0": [100, 200, 300, 400, 500],
            "follower.base.position.1": [1300, 1380, 1450]}
    sweep = write_sweep(tmp_path, grid=grid, duration=2.0)
    out = tmp_path / "out"
    proc = subprocess.Popen(sweep_cmd(str(sweep), "--out", str(out), "--workers", "1",
                                      "--quiet", "--batch", "1"),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=child_default_sigint)
    try:
        wait_for_lines(out / "points.jsonl", 2, proc)
        assert proc.poll() is None, "the sweep ended before it could be interrupted"
        os.kill(proc.pid, signal.SIGINT)
        _, err = proc.communicate(timeout=120)
    finally:
        stop(proc)
    assert proc.returncode == 130, err
    assert "Traceback" not in err and "interrupted (SIGINT)" in err
    rows = _rows(out)
    assert len(rows) == 15  # a valid table of every point
    done = [r for r in rows if r["status"] != "interrupted"]
    assert 2 <= len(done) < 15
    assert {r["criterion"] for r in rows if r["status"] == "interrupted"} == {
        "sweep interrupted (SIGINT)"}
    stored = set(_store_keys(out))
    assert {r["key"] for r in done} == stored
    # Resume: only the rest is computed, each point stored once.
    res = subprocess.run(sweep_cmd(str(sweep), "--out", str(out), "--workers", "1", "--quiet"),
                         capture_output=True, text=True, timeout=300, check=False)
    assert res.returncode == 0, res.stderr
    assert f"({15 - len(stored)} computed now)" in res.stdout
    keys = _store_keys(out)
    assert len(keys) == len(set(keys)) == 15
    assert all(r["status"] != "interrupted" for r in _rows(out))


def test_the_scheduler_gone_mid_sweep_is_a_clear_error(tmp_path, cluster):
    grid = {"follower.base.position.0": [100, 200, 300, 400],
            "follower.base.position.1": [1300, 1380, 1450]}
    sweep = write_sweep(tmp_path, grid=grid, duration=2.0)
    out = tmp_path / "out"
    proc = subprocess.Popen(sweep_cmd(str(sweep), "--out", str(out), "--scheduler",
                                      cluster.address, "--quiet", "--batch", "1"),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        wait_for_lines(out / "points.jsonl", 1, proc)
        stop(cluster.scheduler, signal.SIGKILL)
        _, err = proc.communicate(timeout=120)
    finally:
        stop(proc)
    assert proc.returncode == 1, err
    assert "scheduler stopped answering" in err and "Traceback" not in err
    rows = _rows(out)
    assert len(rows) == 12
    assert {r["key"] for r in rows if r["status"] != "interrupted"} == set(_store_keys(out))
