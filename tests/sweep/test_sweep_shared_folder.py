"""Sweeps run into one folder at the same time compute and store every point once."""

from __future__ import annotations

import json
import re
import subprocess
import threading

import pytest
from sweep_tools import stop, sweep_cmd, write_sweep

from dualarm_qp.bench.runner import code_digest
from dualarm_qp.bench.store import append_result, claim_job
from dualarm_qp.sweep import load_sweep, run_sweep
from dualarm_qp.sweep.points import prepare_points
from dualarm_qp.sweep.worker import empty_record


def _lines(out):
    return [json.loads(line) for line in (out / "points.jsonl").read_text().splitlines()]


def _all_stored_but_one_claimed_elsewhere(tmp_path):
    """A sweep folder where every point is stored except one, which another sweep holds.

    The point held is one whose start cannot be reached (recorded without a cluster).
    """
    spec = load_sweep(write_sweep(tmp_path))
    tasks = prepare_points(spec, code_digest())
    held = next(t for t in tasks if t.start_failure is not None)
    out = tmp_path / "out"
    for t in tasks:
        if t is not held:
            append_result(out / "points.jsonl", {**empty_record("completed", None, ""),
                                                 "key": t.key})
    claim = claim_job(out, held.key, wait=False)
    assert claim is not None
    return spec, out, held, claim


@pytest.mark.slow
def test_a_point_another_sweep_computes_is_taken_from_the_store(tmp_path):
    spec, out, held, claim = _all_stored_but_one_claimed_elsewhere(tmp_path)

    def other_sweep_finishes():
        append_result(out / "points.jsonl", {**empty_record("failed", "start_unreachable",
                                                            "by the other sweep"),
                                             "key": held.key})
        claim.release(stored=True)

    timer = threading.Timer(0.5, other_sweep_finishes)
    timer.start()
    try:
        result = run_sweep(spec, out)
    finally:
        timer.join()
    assert result.computed == 0
    assert [r["key"] for r in _lines(out)].count(held.key) == 1
    row = next(r for r in result.rows if r["key"] == held.key)
    assert row["message"] == "by the other sweep"
    assert not (out / ".claims" / held.key).exists()


@pytest.mark.slow
def test_a_point_left_by_an_interrupted_sweep_is_computed(tmp_path):
    spec, out, held, claim = _all_stored_but_one_claimed_elsewhere(tmp_path)
    timer = threading.Timer(0.5, lambda: claim.release(stored=False))  # stopped, unstored
    timer.start()
    try:
        result = run_sweep(spec, out)
    finally:
        timer.join()
    assert result.computed == 1
    keys = [r["key"] for r in _lines(out)]
    assert keys.count(held.key) == 1 and len(keys) == len(set(keys)) == len(result.rows)
    assert next(r for r in result.rows if r["key"] == held.key)["criterion"] == \
        "start_unreachable"


@pytest.mark.slow
def test_two_sweeps_started_on_one_folder_compute_every_point_once(tmp_path):
    grid = {"follower.base.position.0": [200, 300, 400, 500],
            "follower.base.position.1": [1300, 1380]}
    sweep = write_sweep(tmp_path, grid=grid, duration=1.0)
    out = tmp_path / "out"
    cmd = sweep_cmd(str(sweep), "--out", str(out), "--workers", "1", "--batch", "1",
                    "--quiet")
    procs = [subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                              text=True) for _ in range(2)]
    try:
        outputs = [p.communicate(timeout=300) for p in procs]
    finally:
        for p in procs:
            stop(p)
    assert [p.returncode for p in procs] == [0, 0], outputs
    keys = [r["key"] for r in _lines(out)]
    assert len(keys) == len(set(keys)) == 8  # each point stored once
    computed = [int(re.search(r"\((\d+) computed now\)", o).group(1)) for o, _ in outputs]
    assert sum(computed) == 8 and min(computed) > 0, outputs  # both took part
    assert not list((out / ".claims").iterdir())
