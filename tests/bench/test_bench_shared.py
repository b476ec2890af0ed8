"""Benches sharing one folder: each job computed and stored once, none blocked for good."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

import pytest

from dualarm_qp.bench import BenchSettings, run_bench, run_job
from dualarm_qp.bench.runner import read_config, settings_hash
from dualarm_qp.bench.store import (
    CLAIMS_DIR,
    append_result,
    claim_job,
    load_results,
)
from dualarm_qp.solvers import available_solvers

ROOT = Path(__file__).resolve().parents[2]
LIMITS = str(ROOT / "configs" / "puma_beam_limits.yaml")
SOLVERS = [s for s in ("nullspace", "qp:osqp", "qp:daqp", "reference", "sns")
           if s in available_solvers()]
SHORT = BenchSettings(duration=0.31)


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env.update(OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1",
               PYTHONPATH=str(ROOT) + os.pathsep + env.get("PYTHONPATH", ""))
    return env


@pytest.mark.slow  # four bench processes; the claims are tested in process below
def test_two_benches_on_one_folder_split_the_jobs(tmp_path: Path) -> None:
    cmd = [sys.executable, "-m", "dualarm_qp", "bench", LIMITS, "--solvers", ",".join(SOLVERS),
           "--duration", "0.31", "--no-plots", "--out", str(tmp_path)]
    for expected in (len(SOLVERS), 0):  # the second round: everything stored, both read
        procs = [subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                  text=True, env=_env()) for _ in range(2)]
        outs = [p.communicate(timeout=120) for p in procs]
        computed = 0
        for p, (out, err) in zip(procs, outs, strict=True):
            assert p.returncode == 0, err
            m = re.search(r"\((\d+) of (\d+) jobs computed", out)
            assert m is not None and int(m.group(2)) == len(SOLVERS), out
            computed += int(m.group(1))
            assert all(s in out for s in SOLVERS)  # a full report each
        lines = (tmp_path / "results.jsonl").read_text().splitlines()
        keys = [json.loads(line)["key"] for line in lines]
        assert len(keys) == len(set(keys)) == len(SOLVERS)
        assert computed == expected  # every job computed once in all
    assert not list((tmp_path / CLAIMS_DIR).iterdir())  # claims of stored jobs removed
    assert not [p.name for p in tmp_path.iterdir() if "tmp" in p.name]


def test_a_claimed_job_is_left_to_its_owner_then_reused(tmp_path: Path) -> None:
    cfg = read_config(LIMITS)
    key = settings_hash(cfg, "sns", SHORT)
    other = claim_job(tmp_path, key, wait=False)  # "another bench" computes sns
    assert other is not None
    assert claim_job(tmp_path, key, wait=False) is None  # taken
    calls: list[str] = []
    lines: list[str] = []

    def job(*args: Any) -> dict[str, Any]:
        calls.append(args[1])
        return run_job(*args)

    result: dict[str, Any] = {}
    bench = threading.Thread(target=lambda: result.update(res=run_bench(
        [LIMITS], ["sns", "nullspace"], tmp_path, settings=SHORT, job=job, log=lines.append)))
    bench.start()
    deadline = time.monotonic() + 60
    while "nullspace" not in calls and time.monotonic() < deadline:
        time.sleep(0.01)
    time.sleep(0.2)
    assert calls == ["nullspace"]  # sns left to its owner
    rec = run_job(cfg, "sns", SHORT)
    rec.update(key=key)
    append_result(tmp_path / "results.jsonl", rec)
    other.release(stored=True)
    bench.join(60)
    assert calls == ["nullspace"]
    res = result["res"]
    assert [r["solver"] for r in res.records] == ["sns", "nullspace"] and res.computed == 1
    assert any("waiting" in line for line in lines)
    assert len(load_results(tmp_path / "results.jsonl")) == 2


def test_a_claim_left_by_a_dead_bench_does_not_block(tmp_path: Path) -> None:
    cfg = read_config(LIMITS)
    key = settings_hash(cfg, "nullspace", SHORT)
    (tmp_path / CLAIMS_DIR).mkdir()
    (tmp_path / CLAIMS_DIR / key).write_text("12345\n")  # its lock died with its process
    res = run_bench([LIMITS], ["nullspace"], tmp_path, settings=SHORT)
    assert res.computed == 1


def test_an_abandoned_claim_is_taken_over(tmp_path: Path) -> None:
    """A bench interrupted mid-job releases its claim without storing: the other computes."""
    cfg = read_config(LIMITS)
    key = settings_hash(cfg, "nullspace", SHORT)
    other = claim_job(tmp_path, key, wait=False)
    assert other is not None
    threading.Timer(0.3, lambda: other.release(stored=False)).start()
    res = run_bench([LIMITS], ["nullspace"], tmp_path, settings=SHORT)
    assert res.computed == 1 and res.ok
