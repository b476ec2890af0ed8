"""Sweeps on a real Dask cluster: local or existing, faults, interrupts, resuming."""

from __future__ import annotations

import json
import math
import os
import signal
import subprocess
import time

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


@pytest.mark.slow
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


@pytest.mark.slow
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


@pytest.mark.slow
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


@pytest.mark.slow
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


@pytest.fixture
def in_process_cluster():
    """A scheduler and one single-threaded worker in this process: no process to start."""
    from distributed import LocalCluster

    cluster = LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                           dashboard_address=None)
    try:
        yield cluster
    finally:
        cluster.close()


@pytest.mark.slow
def test_a_sweep_stores_every_point_once_and_a_rerun_computes_none(
        tmp_path, in_process_cluster, capsys):
    """The fast loop's sweep: the driver, the batches, the store, the table and the report
    on a cluster inside this process (the tests above use real worker processes)."""
    sweep = write_sweep(tmp_path)
    out = tmp_path / "out"
    argv = ["sweep", str(sweep), "--out", str(out), "--scheduler",
            in_process_cluster.scheduler_address, "--quiet"]
    assert main(argv) == 0
    assert "(6 computed now)" in capsys.readouterr().out
    rows = _rows(out)
    assert [r["point"] for r in rows] == list(range(6))
    statuses = {(r["follower.base.position.0"], r["follower.base.position.1"]): r["status"]
                for r in rows}
    assert statuses[(300, 1380)] == "completed" and statuses[(0, 1000)] == "failed"
    header, *lines = (out / "results.csv").read_text().splitlines()
    assert header.split(",")[:3] == ["point", "follower.base.position.0",
                                     "follower.base.position.1"] and len(lines) == 6
    assert "data:image/png;base64," in (out / "report.html").read_text()
    assert main(argv) == 0
    assert "(0 computed now)" in capsys.readouterr().out
    for ra, rb in zip(_comparable(_rows(out)), _comparable(rows), strict=True):
        assert ra.keys() == rb.keys() and all(_same(ra[k], rb[k]) for k in ra)
    assert len(_store_keys(out)) == 6


def _third_point_interrupts(monkeypatch, interrupt):
    """Make the third point's run call ``interrupt()`` first; return the real run."""
    from dualarm_qp.sweep import worker

    real, calls = worker.run_point, []

    def run(task):
        calls.append(task)
        if len(calls) == 3:
            interrupt()
        elif len(calls) > 3:  # the points after the Ctrl-C cannot all finish before the
            time.sleep(1.0)   # driver sees it (the compiled step made a point fast)
        return real(task)

    monkeypatch.setattr(worker, "run_point", run)
    return real


def _sweep_argv(tmp_path, cluster) -> tuple:
    """The small sweep's folder and command line, one point per batch on ``cluster``."""
    sweep = write_sweep(tmp_path)
    out = tmp_path / "out"
    return out, ["sweep", str(sweep), "--out", str(out), "--scheduler",
                 cluster.scheduler_address, "--quiet", "--batch", "1"]


@pytest.mark.slow
@pytest.mark.sigint
def test_a_ctrl_c_keeps_the_points_done_and_the_rerun_computes_the_rest(
        tmp_path, in_process_cluster, monkeypatch, capsys):
    """The fast loop's interrupted sweep: a Ctrl-C while the third point runs (the slow
    test above sends it to a real process)."""
    from dualarm_qp.sweep import worker

    real = _third_point_interrupts(monkeypatch, lambda: os.kill(os.getpid(), signal.SIGINT))
    out, argv = _sweep_argv(tmp_path, in_process_cluster)
    assert main(argv) == 130
    err = capsys.readouterr().err
    assert "Traceback" not in err and "interrupted (SIGINT)" in err
    rows = _rows(out)
    assert len(rows) == 6  # a valid table of every point
    done = [r for r in rows if r["status"] != "interrupted"]
    assert 1 <= len(done) < 6
    assert {r["criterion"] for r in rows if r["status"] == "interrupted"} == {
        "sweep interrupted (SIGINT)"}
    stored = set(_store_keys(out))
    assert {r["key"] for r in done} == stored
    monkeypatch.setattr(worker, "run_point", real)
    assert main(argv) == 0
    assert f"({6 - len(stored)} computed now)" in capsys.readouterr().out
    keys = _store_keys(out)
    assert len(keys) == len(set(keys)) == 6
    assert all(r["status"] != "interrupted" for r in _rows(out))


@pytest.mark.sigint
def test_a_ctrl_c_that_something_swallowed_still_stops_the_sweep(
        tmp_path, in_process_cluster, monkeypatch, capsys):
    """A SIGINT whose KeyboardInterrupt never reached the driver (caught on the way, in
    a call into Dask's client) is recorded by the command's handlers: the sweep stops at
    its next poll, as for any Ctrl-C. (The rollouts' own check is turned off here: in
    this in-process cluster they would otherwise see the record first.)"""
    from dualarm_qp import _signals
    from dualarm_qp.experiments import run as run_module

    monkeypatch.setattr(run_module, "raise_if_interrupted", lambda: None)
    # What the command's handler records, without the exception it raises.
    _third_point_interrupts(monkeypatch, lambda: _signals._ACTIVE[-1]._record(signal.SIGINT))
    out, argv = _sweep_argv(tmp_path, in_process_cluster)
    assert main(argv) == 130
    assert "interrupted (SIGINT)" in capsys.readouterr().err
    rows = _rows(out)
    assert len(rows) == 6 and any(r["status"] == "interrupted" for r in rows)


@pytest.mark.slow
def test_the_embedded_cluster_has_the_workers_asked_for_and_closes():
    """``--workers``' cluster of worker processes (the sweeps above run on other ones)."""
    from dualarm_qp.sweep.cluster import open_client, worker_count

    with open_client(workers=1) as client:
        assert worker_count(client) == 1
        assert client.submit(sum, [1, 2]).result(timeout=60) == 3
    assert client.status == "closed"
