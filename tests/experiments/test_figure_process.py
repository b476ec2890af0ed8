"""A run's figures drawn in forked processes (``dualarm-qp run``): the same files as
drawn in the run's own process, an error raised in the run, a dead process replaced,
interrupts left to the command, nothing left running; and the imports that let the
process start before the experiment is even imported."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from test_figures import short_limits_experiment

from dualarm_qp.experiments.figures.process import COST, FigureProcess, can_fork, share
from dualarm_qp.experiments.figures.run_figures import RUN_FIGURES
from dualarm_qp.experiments.run import run_experiment

forking = pytest.mark.skipif(not can_fork(), reason="drawing processes are forked on Linux "
                                                      "with two cores, from one thread")


def pixels(path: Path) -> np.ndarray:
    with Image.open(path) as image:
        return np.asarray(image.convert("RGB"))


def group_ended(pgid: int) -> bool:
    """Whether no process is left in the process group ``pgid``."""
    try:
        os.killpg(pgid, 0)
    except ProcessLookupError:
        return True
    return False


def wait_for(predicate, timeout: float = 10.0) -> bool:
    deadline = time.monotonic() + timeout
    while not predicate():
        if time.monotonic() > deadline:
            return False
        time.sleep(0.01)
    return True


def start_drawing() -> FigureProcess:
    """A drawing process, started once the threads an earlier test left have ended.

    The process forks from one thread only (``can_fork``); in a test run in one process
    a thread of a test before may still be ending (tqdm's monitor of a progress bar).
    """
    assert wait_for(lambda: threading.active_count() == 1), [
        t.name for t in threading.enumerate()]
    figures = FigureProcess.start()
    assert figures is not None
    return figures


def test_the_figures_are_shared_between_two_processes_by_cost():
    one, two = share(list(RUN_FIGURES))
    assert sorted(one + two) == sorted(RUN_FIGURES)
    assert one == [n for n in RUN_FIGURES if n in one]  # each in the order given
    total = sum(COST[n] for n in RUN_FIGURES)
    costs = sorted(sum(COST[n] for n in group) for group in (one, two))
    assert costs[1] - costs[0] <= min(COST.values())  # no figure would even them out more
    assert costs[1] < total
    assert share(["joints.png"]) in ((["joints.png"], []), ([], ["joints.png"]))
    assert share([]) == ([], [])


@pytest.mark.slow
@forking
def test_the_drawing_processes_draw_what_the_run_would(tmp_path):
    exp = short_limits_experiment(tmp_path)
    with start_drawing() as figures:
        pgid = figures.pid
        forked = run_experiment(exp, tmp_path / "forked", progress=False, figures=figures)
    here = run_experiment(exp, tmp_path / "here", progress=False)
    assert forked.summary["outputs"] == here.summary["outputs"]
    for name in RUN_FIGURES:
        assert np.array_equal(pixels(tmp_path / "forked" / name),
                              pixels(tmp_path / "here" / name)), name
    assert figures.pid is None
    assert wait_for(lambda: group_ended(pgid))  # the second one too
    with pytest.raises(ChildProcessError):
        os.waitpid(pgid, os.WNOHANG)  # reaped


@forking
def test_an_error_while_drawing_is_raised_in_the_run(tmp_path):
    exp = short_limits_experiment(tmp_path)
    figures = start_drawing()
    pgid = figures.pid
    with pytest.raises(FileNotFoundError, match=r"trajectory\.csv") as caught:
        figures(tmp_path / "empty", exp)  # no trajectory.csv to draw
    assert "in the figure process" in str(caught.value.__cause__)
    assert figures.pid is None and wait_for(lambda: group_ended(pgid))


@pytest.mark.slow
@forking
def test_a_drawing_process_that_died_is_replaced_by_the_run(tmp_path):
    exp = short_limits_experiment(tmp_path)
    figures = start_drawing()
    os.killpg(figures.pid, signal.SIGKILL)
    outcome = run_experiment(exp, tmp_path / "o", progress=False, figures=figures)
    for name in RUN_FIGURES:
        assert (tmp_path / "o" / name).stat().st_size > 1000, name
    assert "joints.png" in outcome.summary["outputs"]
    assert figures.pid is None


@pytest.mark.slow
@pytest.mark.sigint  # sends SIGINT (to the drawing processes only)
@forking
def test_the_drawing_processes_leave_interrupts_to_the_command(tmp_path):
    """A Ctrl-C at the terminal reaches the foreground process group, the command's: the
    drawing processes are in a group of their own, and ignore SIGINT and SIGTERM
    anyway; the command decides (it finishes writing its set, figures included)."""
    exp = short_limits_experiment(tmp_path)
    with start_drawing() as figures:
        assert os.getpgid(figures.pid) == figures.pid != os.getpgid(0)
        time.sleep(0.2)  # past the fork: its own handlers are in place
        for sig in (signal.SIGINT, signal.SIGTERM):
            os.killpg(figures.pid, sig)
        assert not group_ended(figures.pid)
        run_experiment(exp, tmp_path / "o", progress=False, figures=figures)
    assert (tmp_path / "o" / "report.html").is_file()


class Recorder:
    """Stands in for a FigureProcess: records what it is asked, draws nothing."""

    def __init__(self) -> None:
        self.calls: list[tuple[Path, str]] = []
        self.closed = False

    def __call__(self, out: Path, exp) -> list[str]:
        self.calls.append((Path(out), exp.name))
        return []

    def close(self) -> None:
        self.closed = True


@pytest.mark.parametrize("plots", [True, False])
def test_the_command_starts_the_drawing_first_and_ends_it(tmp_path, monkeypatch, plots):
    import dualarm_qp.experiments.setup as setup
    from dualarm_qp.cli import main

    started: list[Recorder] = []
    order: list[str] = []
    build = setup.build_experiment

    def start() -> Recorder:
        order.append("start")
        started.append(Recorder())
        return started[-1]

    def built(*args, **kwargs):
        order.append("build")
        return build(*args, **kwargs)

    monkeypatch.setattr(FigureProcess, "start", staticmethod(start))
    monkeypatch.setattr(setup, "build_experiment", built)
    out = tmp_path / "o"
    argv = ["run", str(short_config(tmp_path)), "--out", str(out), "--quiet"]
    assert main(argv + ([] if plots else ["--no-plots"])) == 0
    if not plots:
        assert order == ["build"]
        return
    assert order == ["start", "build"]  # it imports matplotlib while the run is prepared
    (figures,) = started
    assert figures.calls == [(out, "puma_beam_limits")] and figures.closed


def test_the_command_starts_the_drawing_before_the_heavy_imports(tmp_path):
    """``dualarm-qp run`` forks the drawing process right after parsing its arguments:
    before NumPy, Pinocchio, Coal and the YAML reader are imported (the run imports them
    while the drawing process imports matplotlib)."""
    config = Path(__file__).resolve().parents[2] / "configs" / "puma_beam_limits.yaml"
    code = textwrap.dedent(f"""
        import os, sys
        from dualarm_qp.experiments.figures.process import FigureProcess

        def start():
            heavy = ("numpy", "pinocchio", "coal", "yaml", "matplotlib")
            print("started;", " ".join(m for m in heavy if m in sys.modules), flush=True)
            os._exit(0)

        FigureProcess.start = staticmethod(start)
        from dualarm_qp.cli import main
        main(["run", {str(config)!r}, "--out", {str(tmp_path / "o")!r}, "--quiet"])
    """)
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "started;"


@pytest.mark.slow
def test_the_drawing_process_can_start_before_the_experiment_is_imported():
    """The command starts it first thing, and it imports matplotlib while the command
    imports the rest: neither the starting nor the figure code it imports may pull in
    the experiment's schema, controller and solvers (nor the start matplotlib)."""
    code = textwrap.dedent("""
        import sys
        import dualarm_qp.cli
        before = set(sys.modules)
        import dualarm_qp.experiments.figures.process
        started = set(sys.modules) - before
        assert not [m for m in started if m.startswith(("matplotlib", "pydantic"))], started
        import dualarm_qp.experiments.figures.run_figures
        drawn = set(sys.modules) - before
        heavy = [m for m in drawn if m.startswith(("pydantic", "yaml", "qpsolvers",
                 "dualarm_qp.experiments.config", "dualarm_qp.experiments.run",
                 "dualarm_qp.experiments.setup", "dualarm_qp.control", "dualarm_qp.solvers"))]
        assert not heavy, heavy
        print("ok")
    """)
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "ok"


@pytest.mark.slow
def test_a_run_without_plots_imports_no_matplotlib(tmp_path):
    code = textwrap.dedent(f"""
        import sys
        from dualarm_qp.cli import main
        code = main(["run", {str(short_config(tmp_path))!r}, "--out", {str(tmp_path / "o")!r},
                     "--quiet", "--no-plots"])
        assert code == 0, code
        assert "matplotlib" not in sys.modules
        assert "PIL" not in sys.modules
        print("ok")
    """)
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip().endswith("ok")


def short_config(tmp_path: Path) -> Path:
    short_limits_experiment(tmp_path, duration=0.062)
    return tmp_path / "short.yaml"
