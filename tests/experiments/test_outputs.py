"""Output folders: fresh or refused, --force replaces only what a run owns, summary last.

Also the in-process interrupt paths (a signal sent by the process to itself at a known
sample), which tests/experiments/test_interrupt.py exercises at random moments.
"""

from __future__ import annotations

import json
import os
import signal
from functools import partial
from pathlib import Path

import pytest
import yaml

from dualarm_qp._io import atomic_write_with
from dualarm_qp._signals import InterruptHandlers, SignalHold
from dualarm_qp.cli import main
from dualarm_qp.experiments import build_experiment, load_config
from dualarm_qp.experiments import reproduce as reproduce_module
from dualarm_qp.experiments import run as run_module
from dualarm_qp.experiments.outputs import owned_entries
from dualarm_qp.experiments.reproduce import CASES, is_reproduction_folder

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
RUN_FILES = ["closure.png", "config.yaml", "grasp.png", "joints.png", "rates.png", "report.html",
             "summary.json", "tracking.png", "trajectory.csv"]
NO_PLOTS_FILES = ["config.yaml", "summary.json", "trajectory.csv"]


def short_config(tmp_path: Path, name: str = "puma_beam_limits.yaml", **controller) -> Path:
    d = yaml.safe_load((CONFIGS / name).read_text())
    d["controller"].update(duration=0.31, **controller)  # 11 samples
    path = tmp_path / f"short_{name}"
    path.write_text(yaml.safe_dump(d))
    return path


@pytest.fixture
def cases(tmp_path) -> Path:
    folder = tmp_path / "cases"
    folder.mkdir()
    for _, name in CASES:
        short = short_config(tmp_path, name)
        short.rename(folder / name)
    return folder


@pytest.fixture(params=[pytest.param(False, id="no-plots"),
                        pytest.param(True, id="plots", marks=pytest.mark.slow)])
def plots(request) -> bool:
    """Whether a test's first run draws its plots (about 2 s a run, hence slow)."""
    return request.param


def plot_options(plots: bool) -> list[str]:
    return [] if plots else ["--no-plots"]


@pytest.fixture(params=[pytest.param(False, id="no-case-plots"),
                        pytest.param(True, id="case-plots", marks=pytest.mark.slow)])
def case_plots(request, monkeypatch) -> bool:
    """Whether a reproduction's cases draw their plots (about 2 s a case, hence slow)."""
    if not request.param:
        real = reproduce_module.run_and_write
        monkeypatch.setattr(reproduce_module, "run_and_write", partial(real, plots=False))
    return request.param


def names(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir())


def summary(folder: Path) -> dict:
    return json.loads((folder / "summary.json").read_text())


def run(config: Path, out: Path, *extra: str) -> int:
    return main(["run", str(config), "--out", str(out), "--quiet", *extra])


@pytest.mark.slow
def test_fresh_folder_holds_exactly_the_listed_set(tmp_path):
    out = tmp_path / "new" / "deeper"
    assert run(short_config(tmp_path), out) == 0
    assert names(out) == RUN_FILES
    s = summary(out)
    assert s["status"] == "completed" and s["completed"] is True
    assert sorted(s["outputs"]) == sorted(set(RUN_FILES) - {"summary.json"})


def test_existing_empty_folder_is_fresh(tmp_path):
    out = tmp_path / "empty"
    out.mkdir()
    assert run(short_config(tmp_path), out, "--no-plots") == 0
    assert names(out) == NO_PLOTS_FILES


def test_used_folder_is_refused_and_left_alone(tmp_path, capsys, plots):
    config = short_config(tmp_path)
    out = tmp_path / "o"
    assert run(config, out, *plot_options(plots)) == 0
    before = {p.name: p.stat().st_mtime_ns for p in out.iterdir()}
    capsys.readouterr()
    assert run(config, out) == 2
    err = capsys.readouterr().err
    assert "not empty" in err and "--force" in err and str(out) in err
    assert len(err.strip().splitlines()) == 1
    assert {p.name: p.stat().st_mtime_ns for p in out.iterdir()} == before


def test_folder_with_other_files_is_refused_without_force(tmp_path, capsys):
    out = tmp_path / "o"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    assert run(short_config(tmp_path), out) == 2
    assert "notes.txt" in capsys.readouterr().err
    assert names(out) == ["notes.txt"]


def test_force_replaces_only_what_a_run_owns(tmp_path, plots):
    config = short_config(tmp_path)
    out = tmp_path / "o"
    assert run(config, out, *plot_options(plots)) == 0
    (out / "notes.txt").write_text("mine")
    (out / "joints.png.bak").write_text("mine too")
    (out / "sub").mkdir()
    (out / ".joints.png.abcd1234.png").write_text("left by a killed run")  # a run's temp
    assert run(config, out, "--force", "--no-plots") == 0
    assert names(out) == ["config.yaml", "joints.png.bak", "notes.txt", "sub",
                          "summary.json", "trajectory.csv"]
    assert (out / "notes.txt").read_text() == "mine"
    # summary.json lists what this run wrote, not the PNGs of the earlier one
    assert summary(out)["outputs"] == ["trajectory.csv", "config.yaml"]


def test_a_folder_in_the_way_of_an_owned_file_is_bad_input(tmp_path, capsys):
    out = tmp_path / "o"
    (out / "summary.json").mkdir(parents=True)
    assert run(short_config(tmp_path), out, "--force", "--no-plots") == 2
    err = capsys.readouterr().err
    assert "summary.json is in the way" in err and "internal error" not in err
    assert (out / "summary.json").is_dir()


def test_force_into_a_fresh_folder_is_fine(tmp_path):
    assert run(short_config(tmp_path), tmp_path / "o", "--force", "--no-plots") == 0


def test_library_run_replaces_an_earlier_set(tmp_path, plots):
    exp = build_experiment(load_config(short_config(tmp_path)))
    out = tmp_path / "o"
    run_module.run_experiment(exp, out, progress=False, plots=plots)
    (out / "notes.txt").write_text("mine")
    outcome = run_module.run_experiment(exp, out, progress=False, plots=False)
    assert names(out) == ["notes.txt", "summary.json", "trajectory.csv"]
    assert outcome.summary["outputs"] == ["trajectory.csv"]


def test_summary_is_written_last(tmp_path, monkeypatch, plots):
    order = []
    real = run_module.write_json

    def spy(path, data):
        order.append(sorted(p.name for p in path.parent.iterdir()))
        real(path, data)

    monkeypatch.setattr(run_module, "write_json", spy)
    assert run(short_config(tmp_path), tmp_path / "o", *plot_options(plots)) == 0
    assert order == [sorted(set(RUN_FILES if plots else NO_PLOTS_FILES) - {"summary.json"})]


def test_an_error_while_writing_leaves_no_half_set(tmp_path, monkeypatch):
    # A figure that raises after the CSV and the config were written: the run's files
    # are removed again (a file of the user's stays), and the error propagates.
    exp = build_experiment(load_config(short_config(tmp_path)))
    out = tmp_path / "o"
    out.mkdir()
    (out / "notes.txt").write_text("mine")

    def broken(*args, **kwargs):
        raise RuntimeError("figure failed")

    import dualarm_qp.experiments.figures as figures_module

    monkeypatch.setattr(figures_module, "write_run_figures", broken)
    with pytest.raises(RuntimeError, match="figure failed"):
        run_module.run_experiment(exp, out, progress=False, plots=True)
    assert names(out) == ["notes.txt"]


def test_owned_entries_match_only_names_and_their_temporary_files(tmp_path):
    for name in ("summary.json", ".summary.json.k2_9ab0x.json", ".summary.json.bak",
                 "summary.json~", "notes.txt"):
        (tmp_path / name).write_text("x")
    found = [p.name for p in owned_entries(tmp_path, ["summary.json"])]
    assert found == [".summary.json.k2_9ab0x.json", "summary.json"]


@pytest.mark.slow
def test_reproduce_twice_into_the_same_folder(tmp_path, cases, case_plots, capsys):
    out = tmp_path / "reproduction"
    argv = ["reproduce", "--out", str(out), "--configs", str(cases), "--quiet"]
    assert main(argv) in (0, 1)
    first = json.loads((out / "reproduce.json").read_text())
    (out / "notes.txt").write_text("mine")
    (out / "case_a" / "notes.txt").write_text("mine too")
    assert main(argv) in (0, 1)  # its own earlier output: replaced, no --force needed
    rep = json.loads((out / "reproduce.json").read_text())
    assert rep["status"] == first["status"] and rep["status"] in ("completed", "failed")
    assert sorted(rep["outputs"]) == ["case_a/", "case_b/", "case_c/", "case_d/",
                                      "fig5_joint3.png", "fig6_grasp.png", "report.html"]
    assert names(out) == ["case_a", "case_b", "case_c", "case_d", "fig5_joint3.png",
                          "fig6_grasp.png", "notes.txt", "report.html", "reproduce.json"]
    page = (out / "report.html").read_text()  # the page that leads to each case
    linked = "report.html" if case_plots else "summary.json"  # no plots: no case report
    assert all(f'href="case_{k}/{linked}"' in page for k in "abcd")
    assert (out / "case_a" / "notes.txt").read_text() == "mine too"
    assert "error" not in capsys.readouterr().err


@pytest.mark.slow
def test_reproduce_recognises_its_files_without_reproduce_json(tmp_path, cases, case_plots):
    out = tmp_path / "reproduction"
    argv = ["reproduce", "--out", str(out), "--configs", str(cases), "--quiet"]
    assert main(argv) in (0, 1)
    (out / "reproduce.json").unlink()  # as if stopped before writing it
    assert is_reproduction_folder(out)
    (out / "case_b" / "mine.txt").write_text("x")
    assert not is_reproduction_folder(out)


@pytest.mark.slow
def test_reproduce_refuses_a_foreign_folder_unless_forced(tmp_path, cases, case_plots,
                                                        capsys):
    out = tmp_path / "busy"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    argv = ["reproduce", "--out", str(out), "--configs", str(cases), "--quiet"]
    assert main(argv) == 2
    assert "--force" in capsys.readouterr().err
    assert names(out) == ["notes.txt"]
    assert main([*argv, "--force"]) in (0, 1)
    assert (out / "notes.txt").read_text() == "mine"
    assert (out / "reproduce.json").is_file()


# --- interrupts at known moments (in process) ---------------------------------------

def _signal_at_sample(monkeypatch, sample: int, sig: int, *, calls: int = 1,
                      swallow: bool = False) -> None:
    """Make the ``calls``-th rollout of run_experiment send ``sig`` to this process."""
    real = run_module.rollout
    seen = {"n": 0}

    def rollout(*args, progress=None, **kwargs):
        seen["n"] += 1
        done = {"samples": 0}

        def prog(path_done: float, time_lost: float) -> None:
            done["samples"] += 1  # called once a sample
            if seen["n"] == calls and done["samples"] == sample:
                try:
                    os.kill(os.getpid(), sig)
                except KeyboardInterrupt:
                    if not swallow:
                        raise
            progress(path_done, time_lost)

        return real(*args, progress=prog, **kwargs)

    monkeypatch.setattr(run_module, "rollout", rollout)


@pytest.mark.sigint
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_interrupted_run_writes_the_partial_trace(tmp_path, monkeypatch, capsys, sig, plots):
    _signal_at_sample(monkeypatch, 5, sig)
    out = tmp_path / "o"
    assert run(short_config(tmp_path), out, *plot_options(plots)) == 130
    s = summary(out)
    assert s["status"] == "interrupted" and s["completed"] is False
    assert s["failure"]["criterion"] == "interrupted"
    assert signal.Signals(sig).name in s["message"]
    assert s["samples"] == 5
    assert len((out / "trajectory.csv").read_text().splitlines()) == 1 + 5
    assert names(out) == (RUN_FILES if plots else NO_PLOTS_FILES)
    captured = capsys.readouterr()
    assert "INTERRUPTED" in captured.out and "interrupted" in captured.err
    assert signal.getsignal(signal.SIGTERM) is signal.SIG_DFL  # restored
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


@pytest.mark.sigint
def test_a_swallowed_interrupt_still_stops_the_run(tmp_path, monkeypatch):
    _signal_at_sample(monkeypatch, 5, signal.SIGINT, swallow=True)
    out = tmp_path / "o"
    assert run(short_config(tmp_path), out, "--no-plots") == 130
    s = summary(out)
    assert s["status"] == "interrupted" and s["samples"] == 5


@pytest.mark.sigint
def test_a_signal_while_writing_waits_for_the_whole_set(tmp_path, monkeypatch, capsys):
    from dualarm_qp.experiments.figures import run_figures

    real = run_figures.grasp_figure
    command = os.getpid()  # the figures may be drawn in a process of their own

    def grasp_figure(*args, **kwargs):
        os.kill(command, signal.SIGINT)  # a (second) Ctrl-C in the middle of writing
        return real(*args, **kwargs)

    monkeypatch.setattr(run_figures, "grasp_figure", grasp_figure)
    out = tmp_path / "o"
    assert run(short_config(tmp_path), out) == 130
    assert names(out) == RUN_FILES  # all of it, and no temporary file
    assert summary(out)["status"] == "completed"
    assert "interrupted" in capsys.readouterr().err


@pytest.mark.slow
def test_interrupted_reproduction_stops_at_the_case(tmp_path, cases, case_plots, monkeypatch,
                                                    capsys):
    rollout = run_module.rollout
    _signal_at_sample(monkeypatch, 3, signal.SIGTERM, calls=2)  # case (b)
    out = tmp_path / "r"
    argv = ["reproduce", "--out", str(out), "--configs", str(cases), "--quiet"]
    assert main(argv) == 130
    rep = json.loads((out / "reproduce.json").read_text())
    assert rep["status"] == "interrupted" and rep["interrupted_case"] == "b"
    assert list(rep["cases"]) == ["a", "b"] and rep["figures"] == []
    assert rep["cases"]["b"]["status"] == "interrupted"
    assert names(out) == ["case_a", "case_b", "report.html", "reproduce.json"]
    assert "Interrupted in case (b)" in (out / "report.html").read_text()
    assert summary(out / "case_b")["samples"] == 3
    assert "interrupted in case (b)" in capsys.readouterr().err
    # and the next reproduction into it just works
    monkeypatch.setattr(run_module, "rollout", rollout)
    assert main(argv) in (0, 1)
    rep = json.loads((out / "reproduce.json").read_text())
    assert rep["status"] != "interrupted" and list(rep["cases"]) == ["a", "b", "c", "d"]


def _signal_in_first_step(monkeypatch, sig: int) -> None:
    """Make the first rollout's first controller step send ``sig`` to this process: the
    rollout stops before its first sample is recorded (0 samples)."""
    real = run_module.rollout
    seen = {"n": 0}

    def rollout(controller, *args, **kwargs):
        seen["n"] += 1
        if seen["n"] == 1:
            step = controller.step

            def first_step(*a, **k):
                controller.step = step
                os.kill(os.getpid(), sig)
                return step(*a, **k)

            controller.step = first_step
        return real(controller, *args, **kwargs)

    monkeypatch.setattr(run_module, "rollout", rollout)


@pytest.mark.sigint
def test_a_reproduction_stopped_before_its_first_sample_is_recorded(tmp_path, cases,
                                                                     monkeypatch, capsys):
    """A signal in case (a)'s first step: 0 samples, whose grasp is null in the record.
    The page used to fail on it (TypeError), leaving case_a/ without reproduce.json."""
    _signal_in_first_step(monkeypatch, signal.SIGTERM)
    out = tmp_path / "r"
    argv = ["reproduce", "--out", str(out), "--configs", str(cases), "--quiet"]
    assert main(argv) == 130
    assert names(out) == ["case_a", "report.html", "reproduce.json"]
    rep = json.loads((out / "reproduce.json").read_text())
    assert rep["status"] == "interrupted" and rep["interrupted_case"] == "a"
    assert rep["outputs"] == ["case_a/", "report.html"]
    assert rep["cases"]["a"]["samples"] == 0 and rep["cases"]["a"]["grasp_start_m"] is None
    assert summary(out / "case_a")["samples"] == 0
    page = (out / "report.html").read_text()
    assert "Interrupted in case (a)" in page and "grasp n/a -&gt; n/a" in page
    assert "interrupted in case (a)" in capsys.readouterr().err


def test_signal_hold_delivers_after_the_block():
    with InterruptHandlers() as handlers:
        with pytest.raises(KeyboardInterrupt, match="SIGTERM"):
            with SignalHold():
                os.kill(os.getpid(), signal.SIGTERM)
                reached = True
        assert reached and handlers.signum == signal.SIGTERM


def test_atomic_write_leaves_no_temporary_file_on_interrupt(tmp_path):
    target = tmp_path / "f.png"

    def writer(tmp: str) -> None:
        Path(tmp).write_text("half")
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        atomic_write_with(target, writer)
    assert names(tmp_path) == []
