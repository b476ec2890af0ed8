"""The config x solver bench: fields, resume without recomputation, interrupted runs."""

from __future__ import annotations

import json
import os
import signal
import time
from pathlib import Path
from typing import Any

import pytest

from dualarm_qp._signals import InterruptHandlers, SignalHold, interrupt_requested
from dualarm_qp.bench import BenchSettings, keys, run_bench, run_job, runner, write_report
from dualarm_qp.bench.bare import BareProbe
from dualarm_qp.bench.report import COLUMNS
from dualarm_qp.bench.runner import BackendInterrupted, BenchInterrupted
from dualarm_qp.bench.store import append_result, load_results
from dualarm_qp.errors import ConfigError, SolverNotFoundError
from dualarm_qp.experiments.reproduce import bundled_config
from dualarm_qp.solvers import available_solvers

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


@pytest.mark.slow
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
    with pytest.raises(BenchInterrupted) as stop:
        run_bench([CONFIG], ["nullspace", "reference", "sns"], tmp_path, settings=SHORT,
                  job=Counting(interrupt_after=1))
    assert [r["solver"] for r in stop.value.result.records] == ["nullspace"]
    assert stop.value.result.interrupted and stop.value.result.planned == 3
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


def test_swallowed_signal_keeps_the_job_out_of_the_store(tmp_path: Path) -> None:
    """A SIGTERM during a job that some code swallows still stops the bench unstored."""

    def swallowing(*args: Any) -> dict[str, Any]:
        rec = run_job(*args)
        try:
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(0.05)  # the handler runs here at the latest
        except KeyboardInterrupt:
            pass  # swallowed on the way
        return rec

    with pytest.raises(BenchInterrupted) as stop:
        run_bench([LIMITS], ["nullspace", "sns"], tmp_path, settings=SHORT, job=swallowing)
    assert stop.value.signum == signal.SIGTERM and stop.value.result.records == []
    assert load_results(tmp_path / "results.jsonl") == {}
    assert signal.getsignal(signal.SIGTERM) is signal.SIG_DFL  # handlers restored


def _interrupted_osqp(monkeypatch: pytest.MonkeyPatch) -> None:
    """osqp answering as it does when its own handler caught a SIGINT that Python ignores."""
    from dualarm_qp.solvers.backends import BackendAnswer, osqp_

    monkeypatch.setattr(osqp_.OSQPNative, "solve", lambda self, problem:
                        BackendAnswer(problem, None, False, False, "interrupted"))


@pytest.mark.skipif("qp:osqp" not in available_solvers(), reason="osqp not installed")
def test_job_with_an_interrupted_backend_is_never_stored(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    _interrupted_osqp(monkeypatch)
    with pytest.raises(BackendInterrupted, match="interrupt"):
        run_job(runner.read_config(LIMITS), "qp:osqp", SHORT)
    calls = Counting()
    with pytest.raises(BenchInterrupted):
        run_bench([LIMITS], ["nullspace", "qp:osqp"], tmp_path, settings=SHORT, job=calls)
    assert calls.calls == 1 + runner.BACKEND_INTERRUPT_RETRIES + 1  # retried, never stored
    assert [r["solver"] for r in load_results(tmp_path / "results.jsonl").values()] == [
        "nullspace"]
    monkeypatch.undo()  # the backend answers again: the resume computes the job
    res = run_bench([LIMITS], ["nullspace", "qp:osqp"], tmp_path, settings=SHORT)
    assert res.computed == 1 and res.ok


def test_a_transient_backend_interrupt_is_retried(tmp_path: Path) -> None:
    seen = []

    def flaky(*args: Any) -> dict[str, Any]:
        seen.append(args[1])
        if len(seen) == 1:
            raise BackendInterrupted("osqp: interrupted")
        return run_job(*args)

    res = run_bench([LIMITS], ["nullspace"], tmp_path, settings=SHORT, job=flaky)
    assert seen == ["nullspace", "nullspace"] and res.computed == 1
    assert len((tmp_path / "results.jsonl").read_text().splitlines()) == 1


@pytest.mark.sigint
def test_handlers_keep_an_ignored_sigint_ignored() -> None:
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        with InterruptHandlers() as handlers, SignalHold() as hold:
            assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
            signal.raise_signal(signal.SIGINT)
        assert handlers.signum is None and hold.signum is None
    finally:
        signal.signal(signal.SIGINT, previous)


def test_a_hold_defers_a_signal_to_the_end_of_its_block() -> None:
    done = []
    with InterruptHandlers() as handlers, pytest.raises(KeyboardInterrupt):
        with SignalHold(), SignalHold():  # nested: passed on once, by the outer hold
            signal.raise_signal(signal.SIGTERM)
            done.append(True)  # reached: the block runs to its end
        done.append(False)  # not reached: raised when the outer hold ends
    assert done == [True] and handlers.signum == signal.SIGTERM


def test_nested_handlers_record_in_the_outer_ones() -> None:
    """A bench's handlers inside the command line's: both know of the signal."""
    with InterruptHandlers() as outer:
        with InterruptHandlers() as inner:
            with pytest.raises(KeyboardInterrupt, match="SIGTERM"):
                signal.raise_signal(signal.SIGTERM)
            assert interrupt_requested() == "SIGTERM"
        assert signal.getsignal(signal.SIGTERM) is outer  # restored to the outer
    assert inner.signum == outer.signum == signal.SIGTERM
    assert interrupt_requested() is None


def test_changed_code_invalidates_stored_rows(tmp_path: Path,
                                              monkeypatch: pytest.MonkeyPatch) -> None:
    digest = runner.code_digest()
    assert len(digest) == 64 and digest == runner.code_digest()
    first = run_bench([LIMITS], ["nullspace"], tmp_path, settings=SHORT)
    assert first.records[0]["code"] == digest
    monkeypatch.setattr(keys, "code_digest", lambda: "0" * 64)  # what the job keys hold
    again = Counting()
    res = run_bench([LIMITS], ["nullspace"], tmp_path, settings=SHORT, job=again)
    assert again.calls == 1 and res.computed == 1
    assert res.records[0]["key"] != first.records[0]["key"]
    monkeypatch.undo()
    back = Counting()
    run_bench([LIMITS], ["nullspace"], tmp_path, settings=SHORT, job=back)
    assert back.calls == 0  # the rows of this code are still there


def test_job_failure_reasons() -> None:
    ok = {"steps_run": 11, "success_rate": 0.7, "message": "stopped at step 8"}
    assert runner.job_failure(ok) is None
    assert runner.job_failure({"error": "SolverError: boom"}) == "SolverError: boom"
    nothing = {"steps_run": 0, "success_rate": 0.0, "message": "step 0: no answer"}
    assert runner.job_failure(nothing) == "no usable step: step 0: no answer"


@pytest.mark.sigint
@pytest.mark.skipif("qp:osqp" not in available_solvers(), reason="osqp not installed")
def test_bare_probe_passes_on_a_sigint_that_osqp_swallowed(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """qpsolvers returns osqp's "interrupted" answer as a plain failure; the probe re-raises."""
    from types import SimpleNamespace

    import qpsolvers

    from dualarm_qp.solvers.registry import get_solver

    answer = SimpleNamespace(solve_time=1e-5,
                             extras={"info": SimpleNamespace(status="interrupted")})
    monkeypatch.setattr(qpsolvers, "solve_problem", lambda *a, **k: answer)
    cfg = runner.read_config(LIMITS)
    problem = runner.canonical_steps(cfg, SHORT)[0]
    probe = BareProbe.make(get_solver("qp:osqp"))
    assert probe is not None
    with pytest.raises(KeyboardInterrupt):  # Python's own SIGINT handler
        probe.solve_time(problem)
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:  # SIGINT ignored: the answer is still void
        with pytest.raises(BackendInterrupted):
            probe.solve_time(problem)
    finally:
        signal.signal(signal.SIGINT, previous)
