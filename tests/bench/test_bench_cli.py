"""``dualarm-qp bench``: outputs, resume, exit codes."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest

from dualarm_qp.cli import main
from dualarm_qp.experiments.reproduce import bundled_config

CONFIG = str(bundled_config("puma_beam_sliding_s7_100.yaml"))


def test_bench_command(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    args = ["bench", CONFIG, "--solvers", "reference,nullspace", "--out", str(tmp_path),
            "--duration", "0.124", "--quiet"]
    assert main(args) == 0
    out = capsys.readouterr().out
    assert "nullspace" in out and "step med us" in out and "2 of 2 jobs computed" in out
    rows = list(csv.DictReader(open(tmp_path / "bench.csv", encoding="utf-8")))
    assert [r["solver"] for r in rows] == ["reference", "nullspace"]
    assert (tmp_path / "bench.png").exists()
    assert main(args) == 0
    assert "0 of 2 jobs computed" in capsys.readouterr().out


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
