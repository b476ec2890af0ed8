"""The config x solver bench: fields, resume without recomputation, interrupted runs."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from dualarm_qp.bench import BenchSettings, run_bench, run_job, write_report
from dualarm_qp.bench.report import COLUMNS
from dualarm_qp.bench.store import append_result, load_results
from dualarm_qp.errors import ConfigError, SolverNotFoundError
from dualarm_qp.experiments.reproduce import bundled_config

CONFIG = str(bundled_config("puma_beam_sliding_s7_100.yaml"))
#: With speed limits: a hard-limit solver's run on the paper's configs fails at its first
#: (unlimited) sample on the grasp closure, which leaves nothing to time.
LIMITS = str(Path(__file__).resolve().parents[2] / "configs" / "puma_beam_limits.yaml")
SHORT = BenchSettings(duration=0.31)  # 11 steps


class Counting:
    """A job function that counts its calls and can raise after a number of jobs."""

    def __init__(self, interrupt_after: int | None = None) -> None:
        self.calls = 0
        self.interrupt_after = interrupt_after

    def __call__(self, *args: Any) -> dict[str, Any]:
        if self.interrupt_after is not None and self.calls >= self.interrupt_after:
            raise KeyboardInterrupt
        self.calls += 1
        return run_job(*args)


def test_bench_writes_every_field(tmp_path: Path) -> None:
    res = run_bench([LIMITS], ["nullspace", "qp:daqp"], tmp_path, settings=SHORT)
    assert res.ok and res.computed == 2
    rows = write_report(tmp_path, res.records, {"machine": res.machine})
    for name in ("bench.json", "bench.csv", "bench.png", "results.jsonl"):
        assert (tmp_path / name).exists()
    doc = json.loads((tmp_path / "bench.json").read_text())
    assert [r["solver"] for r in doc["rows"]] == ["nullspace", "qp:daqp"]
    header = (tmp_path / "bench.csv").read_text().splitlines()[0].split(",")
    assert tuple(header) == COLUMNS
    for row in rows:
        assert row["steps"] == 11 and row["success_rate"] == 1.0
        assert row["status_optimal"] + row["status_recovering"] == 11
        for key in ("step_time_median_s", "step_time_p99_s", "kinematics_time_median_s",
                    "assembly_time_median_s", "solve_time_median_s"):
            assert row[key] > 0
        assert row["step_time_median_s"] >= row["solve_time_median_s"]
        assert row["bound_violation_max"] <= 1e-7
        assert row["objective_gap_steps"] == 11
        assert row["objective_gap_rel_max"] <= 1e-7  # both solve the QP exactly
    assert rows[1]["bare_solve_time_median_s"] > 0  # qp:* solvers get the bare time


def test_second_run_recomputes_nothing(tmp_path: Path) -> None:
    first = Counting()
    run_bench([CONFIG], ["nullspace", "reference"], tmp_path, settings=SHORT, job=first)
    again = Counting()
    res = run_bench([CONFIG], ["nullspace", "reference"], tmp_path, settings=SHORT, job=again)
    assert first.calls == 2 and again.calls == 0 and res.computed == 0
    assert [r["solver"] for r in res.records] == ["nullspace", "reference"]
    # Other settings are another key: computed afresh.
    other = Counting()
    run_bench([CONFIG], ["nullspace"], tmp_path, settings=BenchSettings(duration=0.124),
              job=other)
    assert other.calls == 1


def test_interrupted_bench_resumes_where_it_stopped(tmp_path: Path) -> None:
    with pytest.raises(KeyboardInterrupt):
        run_bench([CONFIG], ["nullspace", "reference", "sns"], tmp_path, settings=SHORT,
                  job=Counting(interrupt_after=1))
    assert len(load_results(tmp_path / "results.jsonl")) == 1
    rest = Counting()
    res = run_bench([CONFIG], ["nullspace", "reference", "sns"], tmp_path, settings=SHORT,
                    job=rest)
    assert rest.calls == 2 and res.computed == 2
    assert [r["solver"] for r in res.records] == ["nullspace", "reference", "sns"]


def test_torn_last_line_is_dropped(tmp_path: Path) -> None:
    store = tmp_path / "results.jsonl"
    append_result(store, {"key": "a", "v": 1})
    with open(store, "ab") as fh:
        fh.write(b'{"key": "b", "v"')  # a write cut short
    assert list(load_results(store)) == ["a"]
    append_result(store, {"key": "c", "v": 3})
    assert list(load_results(store)) == ["a", "c"]


def test_bad_input_is_reported_before_any_job(tmp_path: Path) -> None:
    job = Counting()
    with pytest.raises(SolverNotFoundError):
        run_bench([CONFIG], ["nullspace", "qp:nope"], tmp_path, job=job)
    with pytest.raises(ConfigError):
        run_bench([tmp_path / "missing.yaml"], ["nullspace"], tmp_path, job=job)
    assert job.calls == 0 and not (tmp_path / "results.jsonl").exists()
