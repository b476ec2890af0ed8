"""The command line behaves like a Unix tool; importing the library changes nothing."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from dualarm_qp.cli import EXIT_BROKEN_PIPE, main

posix_only = pytest.mark.skipif(os.name != "posix", reason="POSIX pipes and signals")


def _python(code: str, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-c", textwrap.dedent(code)], cwd=cwd,
                          capture_output=True, text=True, check=False, timeout=120)


@pytest.mark.slow
@posix_only
def test_closed_stdout_ends_quietly():
    proc = subprocess.Popen([sys.executable, "-m", "dualarm_qp.cli", "solvers"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    assert proc.stdout is not None
    proc.stdout.close()  # the reader is gone before the first line is written
    _, err = proc.communicate(timeout=120)
    assert err.decode() == ""
    assert proc.returncode == EXIT_BROKEN_PIPE


@pytest.mark.slow
@posix_only
def test_solvers_into_head_is_quiet():
    cmd = f"'{sys.executable}' -m dualarm_qp.cli solvers | head -1"
    proc = subprocess.run(["sh", "-c", cmd], capture_output=True, text=True, check=False,
                          timeout=120)
    assert proc.returncode == 0
    assert proc.stdout.startswith("SOLVER")
    assert proc.stderr == ""


@pytest.mark.parametrize("argv", [["--debug", "solvers"], ["solvers", "--debug"]])
def test_debug_is_accepted_before_and_after_the_command(argv, monkeypatch, capsys):
    def broken():
        raise RuntimeError("boom")

    monkeypatch.setattr("dualarm_qp.solvers.list_solvers", broken)
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert "Traceback" in err and "internal error: RuntimeError: boom" in err


def test_without_debug_no_traceback(monkeypatch, capsys):
    def broken():
        raise RuntimeError("boom")

    monkeypatch.setattr("dualarm_qp.solvers.list_solvers", broken)
    assert main(["solvers"]) == 1
    err = capsys.readouterr().err
    assert "Traceback" not in err and "rerun with --debug" in err


def test_debug_after_run_is_accepted(tmp_path, capsys):
    assert main(["run", str(tmp_path / "missing.yaml"), "--debug"]) == 2
    assert "file not found" in capsys.readouterr().err


@pytest.mark.sigint
def test_an_error_caused_by_an_interrupt_is_an_interrupt(monkeypatch, capsys):
    """Ctrl-C during an extension module's import surfaces as "ImportError:
    initialization failed"; the command must still say "interrupted" and exit 130."""

    def cut_short():
        try:
            os.kill(os.getpid(), signal.SIGINT)
        except KeyboardInterrupt as err:
            raise ImportError("initialization failed") from err

    monkeypatch.setattr("dualarm_qp.solvers.list_solvers", cut_short)
    assert main(["solvers"]) == 130
    err = capsys.readouterr().err
    assert "internal error" not in err and "interrupted" in err
    # The error is named on the same line: a fault of the command's own that came after
    # an interrupt (a page that cannot be written for a run stopped at its first sample)
    # would otherwise be hidden behind "interrupted".
    assert "then ImportError: initialization failed (rerun with --debug" in err


@pytest.mark.slow
def test_import_selects_no_backend_and_no_pyplot(tmp_path):
    proc = _python("""
        import sys, warnings
        import matplotlib
        matplotlib.use("svg")
        import numpy, scipy.linalg, scipy.optimize, scipy.sparse  # their own filters
        filters = list(warnings.filters)
        import dualarm_qp, dualarm_qp.cli, dualarm_qp.experiments, dualarm_qp.solvers
        import dualarm_qp.experiments.figures, dualarm_qp.bench.report
        from pathlib import Path
        from dualarm_qp.experiments.figures.canvas import new_figure, save_png
        fig = new_figure()
        fig.subplots().semilogy([0, 1, 2], [1e-9, 1e-8, 1e-9])
        save_png(fig, Path("closure.png"))
        assert matplotlib.get_backend() == "svg", matplotlib.get_backend()
        assert "matplotlib.pyplot" not in sys.modules
        assert warnings.filters == filters, "warnings filters changed at import"
        print("ok")
    """, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "ok"
    assert (tmp_path / "closure.png").stat().st_size > 1000


@pytest.mark.slow
def test_the_library_and_the_help_import_no_optimiser():
    """`import dualarm_qp` and `dualarm-qp --help` stay light: no scipy.optimize either,
    and no 3D viewer (meshcat, its server's zmq, viser) until a view is drawn."""
    proc = _python("""
        import sys
        import dualarm_qp
        import dualarm_qp.viz
        from dualarm_qp.cli import main
        try:
            main(["--help"])
        except SystemExit:
            pass
        heavy = [m for m in ("scipy.optimize", "matplotlib", "meshcat", "zmq", "viser",
                             "dask", "distributed", "pyarrow")
                 if m in sys.modules]
        assert not heavy, heavy
        print("ok")
    """)
    assert proc.returncode == 0, proc.stderr


@pytest.mark.slow
def test_importing_the_library_or_the_help_imports_no_matplotlib():
    proc = _python("""
        import sys
        import dualarm_qp
        import dualarm_qp.experiments
        assert "matplotlib" not in sys.modules, "import dualarm_qp(.experiments)"
        from dualarm_qp.cli import main
        try:
            main(["--help"])
        except SystemExit:
            pass
        assert "matplotlib" not in sys.modules, "dualarm-qp --help"
        print("ok")
    """)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip().endswith("ok")
