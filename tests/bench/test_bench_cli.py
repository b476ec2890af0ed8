"""``dualarm-qp bench``: outputs, resume, exit codes."""

from __future__ import annotations

import csv
import os
import re
import signal
from pathlib import Path

import pytest

from dualarm_qp.cli import main
from dualarm_qp.experiments.reproduce import bundled_config

CONFIG = str(bundled_config("puma_beam_sliding_s7_100.yaml"))


@pytest.mark.slow
def test_bench_command(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    args = ["bench", CONFIG, "--solvers", "reference,nullspace", "--out", str(tmp_path),
            "--duration", "0.124", "--quiet"]
    assert main(args) == 0
    out = capsys.readouterr().out
    assert "nullspace" in out and "step med us" in out
    assert "(2 of 2 jobs computed now)" in out  # nothing resumed, and it says so
    assert "\n  solve/bare: " in out and "\n  margin rad: " in out  # the columns' legend
    rows = list(csv.DictReader(open(tmp_path / "bench.csv", encoding="utf-8")))
    assert [r["solver"] for r in rows] == ["reference", "nullspace"]
    assert (tmp_path / "bench.png").exists()
    assert main(args) == 0
    assert "(0 of 2 jobs computed now, 2 reused from the store (resumed))" in (
        capsys.readouterr().out)


def test_bench_bad_input_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["bench", CONFIG, "--solvers", "qp:nope", "--out", str(tmp_path)]) == 2
    assert "unknown solver 'qp:nope'" in capsys.readouterr().err
    assert main(["bench", str(tmp_path / "none.yaml"), "--solvers", "nullspace",
                 "--out", str(tmp_path)]) == 2
    assert "file not found" in capsys.readouterr().err
    assert main(["bench", CONFIG, "--repeat", "0", "--out", str(tmp_path)]) == 2


def test_bench_missing_backend_names_extra(tmp_path: Path,
                                           capsys: pytest.CaptureFixture[str]) -> None:
    from dualarm_qp.solvers import list_solvers

    missing = [s for s in list_solvers() if not s.available and s.extra]
    if not missing:
        pytest.skip("every backend is installed here")
    assert main(["bench", CONFIG, "--solvers", missing[0].name, "--out", str(tmp_path)]) == 2
    assert f"dualarm-qp[{missing[0].extra}]" in capsys.readouterr().err


def test_bench_no_solver_named_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    for given in ("", " , ,", ","):
        assert main(["bench", CONFIG, "--solvers", given, "--out", str(tmp_path)]) == 2
        err = capsys.readouterr().err
        assert "names no solver" in err and "nullspace" in err and "reference" in err
    assert not (tmp_path / "results.jsonl").exists()


def test_bench_all_jobs_failing_exit_1_with_reasons(
        tmp_path: Path, capsys: pytest.CaptureFixture[str],
        monkeypatch: pytest.MonkeyPatch) -> None:
    from dualarm_qp.bench import runner
    from dualarm_qp.errors import SolverError

    def broken(config, solver, *args):  # type: ignore[no-untyped-def]
        raise SolverError(f"{solver} exploded")

    monkeypatch.setattr(runner, "run_job", broken)
    args = ["bench", CONFIG, "--solvers", "reference,nullspace", "--out", str(tmp_path),
            "--duration", "0.124", "--quiet", "--no-plots"]
    assert main(args) == 1
    cap = capsys.readouterr()
    assert "reference exploded" in cap.out and "nullspace exploded" in cap.out
    assert "ERROR" in cap.out and "nan" not in cap.out
    assert "2 of 2 jobs failed (all of them)" in cap.err
    rows = list(csv.DictReader(open(tmp_path / "bench.csv", encoding="utf-8")))
    assert [r["error"] for r in rows] == ["SolverError: reference exploded",
                                          "SolverError: nullspace exploded"]
    assert main(args) == 1  # stored failures are reported again on resume
    assert "0 of 2 jobs computed" in capsys.readouterr().out


def test_bench_jobs_without_a_usable_step_fail(
        tmp_path: Path, capsys: pytest.CaptureFixture[str],
        monkeypatch: pytest.MonkeyPatch) -> None:
    """A run that stops before its first usable step gave nothing to compare: exit 1."""
    from dualarm_qp.control.controller import DualArmController
    from dualarm_qp.errors import SolverError

    def no_answer(self, state, *, scale_max=1.0):  # type: ignore[no-untyped-def]
        raise SolverError("no answer at all")

    monkeypatch.setattr(DualArmController, "step", no_answer)
    assert main(["bench", CONFIG, "--solvers", "nullspace", "--out", str(tmp_path),
                 "--duration", "0.124", "--quiet", "--no-plots"]) == 1
    cap = capsys.readouterr()
    assert "no usable step" in cap.out and "no answer at all" in cap.out
    row = next(csv.DictReader(open(tmp_path / "bench.csv", encoding="utf-8")))
    assert row["error"].startswith("no usable step") and "no answer at all" in row["message"]


@pytest.mark.sigint
def test_a_ctrl_c_during_a_job_exits_130_and_the_rerun_resumes(
        tmp_path: Path, capsys: pytest.CaptureFixture[str],
        monkeypatch: pytest.MonkeyPatch) -> None:
    """The fast loop's bench interrupt (tests/bench/test_bench_interrupt.py sends the
    signals to real processes at random moments): the job under way is not stored."""
    from dualarm_qp.bench import runner

    real = runner.run_job

    def interrupted_second(config, solver, *args):  # type: ignore[no-untyped-def]
        if solver == "nullspace":
            os.kill(os.getpid(), signal.SIGINT)
        return real(config, solver, *args)

    monkeypatch.setattr(runner, "run_job", interrupted_second)
    args = ["bench", CONFIG, "--solvers", "reference,nullspace", "--out", str(tmp_path),
            "--duration", "0.124", "--quiet", "--no-plots"]
    assert main(args) == 130
    cap = capsys.readouterr()
    assert "interrupted (SIGINT): 1 of 2 jobs done and stored" in cap.err
    assert "Traceback" not in cap.err
    assert len((tmp_path / "results.jsonl").read_text().splitlines()) == 1
    monkeypatch.setattr(runner, "run_job", real)
    assert main(args) == 0
    assert "1 of 2 jobs computed" in capsys.readouterr().out


def test_a_solver_that_cannot_take_the_files_limits_is_not_applicable(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    # Collision rows are general inequalities: SNS takes boxes only, so the bench lists
    # it as not run (exit 0), not as a failed job.
    import yaml

    raw = yaml.safe_load(open(CONFIG, encoding="utf-8"))
    raw["collision"] = {"enabled": True}
    raw["scene"] = {"obstacles": [{"name": "post", "sphere": {"radius": 50},
                                   "pose": {"position": [2000, 2000, 2000]}}]}
    cfg = tmp_path / "with_post.yaml"
    cfg.write_text(yaml.safe_dump(raw), encoding="utf-8")
    args = ["bench", str(cfg), "--solvers", "nullspace,sns", "--out", str(tmp_path / "b"),
            "--duration", "0.124", "--quiet", "--no-plots"]
    assert main(args) == 0
    out = capsys.readouterr().out
    assert "Not applicable (not run):" in out
    assert re.search(r"sns: \S*with_post\.yaml: solver 'sns' takes boxes only, and the "
                     r"limit 'collision' gives rows", out), out
    assert "Failed jobs" not in out
    rows = {r["solver"]: r for r in csv.DictReader(open(tmp_path / "b" / "bench.csv",
                                                        encoding="utf-8"))}
    assert rows["sns"]["not_applicable"] and not rows["sns"]["error"]
    assert float(rows["nullspace"]["success_rate"]) > 0.0  # it ran
