"""Run an experiment and write its outputs (CSV, JSON, PNG, HTML).

The outputs of a run form one set: ``summary.json`` is written last and lists the
other files, so a folder whose ``summary.json`` exists holds exactly what it lists.
The set is written with SIGINT and SIGTERM held
(:class:`~dualarm_qp._signals.SignalHold`): an interrupt during the rollout stops it and
the samples done so far are written as an ``interrupted`` run; an interrupt while the
files are written waits until they all are.
"""

from __future__ import annotations

import platform
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

from .._io import write_text
from .._signals import SignalHold, raise_if_interrupted
from ..control.controller import DualArmController
from ..control.measured import record_readings
from ..control.plant import Plant
from ..control.rollout import RolloutResult, rollout
from .limits_kept import limits_kept
from .outputs import csv_columns, remove_owned, write_json, write_trace_csv
from .setup import Experiment

if TYPE_CHECKING:
    from .figures.rundata import RunData

#: The files a run owns in its output folder (``summary.json`` lists the others written).
OUTPUT_FILES = ("summary.json", "trajectory.csv", "joints.png", "rates.png", "grasp.png",
                "tracking.png", "closure.png", "clearance.png", "report.html", "config.yaml",
                "animation.html")

#: What writes a run's PNG figures: ``figures(out, exp)`` returns the file names.
FigureWriter = Callable[[Path, Experiment], list[str]]


@runtime_checkable
class FiguresAhead(Protocol):
    """A figure writer that takes the run's trace before the run's files are written.

    What :class:`~.figures.process.FigureProcess` is: :meth:`submit` sends the job and
    returns at once, calling the writer waits for its figures, :meth:`close` ends it
    (nothing of it writes any more).
    """

    def __call__(self, out: Path, exp: Experiment) -> list[str]:
        """Wait for the figures of the run in ``out``; return their file names."""
        ...

    def submit(self, out: Path, exp: Experiment, data: RunData) -> None:
        """Send the run's job with its trace ``data``, without waiting."""
        ...

    def close(self) -> None:
        """End the writer: nothing of it writes any more."""
        ...


#: What ``summary.json``'s ``status`` says.
STATUSES = ("completed", "failed", "interrupted")


@dataclass
class RunOutcome:
    """What :func:`run_experiment` did.

    Attributes
    ----------
    result : RolloutResult
        The rollout (its trace may be partial when the run failed).
    summary : dict
        The content of ``summary.json``.
    out_dir : Path or None
        Where the files went (None when nothing was written).
    """

    result: RolloutResult
    summary: dict[str, Any]
    out_dir: Path | None

    @property
    def ok(self) -> bool:
        """Whether the whole duration was run."""
        return self.result.completed

    @property
    def interrupted(self) -> bool:
        """Whether an interrupt (Ctrl-C, SIGTERM) stopped the rollout."""
        return run_status(self.result) == "interrupted"


def run_status(result: RolloutResult) -> str:
    """Return ``"completed"``, ``"interrupted"`` or ``"failed"`` (one of :data:`STATUSES`)."""
    if result.failure is None:
        return "completed"
    return "interrupted" if result.failure.criterion == "interrupted" else "failed"


#: What the progress bar shows: the share of the path done, then the time lost.
PROGRESS_FORMAT = "{desc}: {percentage:3.0f}% of the path |{bar}| {elapsed}<{remaining}{postfix}"


def _progress(label: str, show: bool) -> tuple[Any, Callable[[float, float], None]]:
    """Return a progress bar (or None) and the rollout's per-sample callback.

    The bar counts the path ``D(t)`` in percent, not samples: a task that the limits
    slow runs more samples than the nominal count, and its bar still ends at 100%. Its
    postfix gives the time lost to the slowing so far [s]. The callback also stops the
    rollout when the command line received an interrupt that some code swallowed
    (:func:`~dualarm_qp._signals.raise_if_interrupted`).
    """
    bar = None
    if show:
        from tqdm import tqdm

        bar = tqdm(total=100.0, desc=label, leave=False, file=sys.stderr,
                   bar_format=PROGRESS_FORMAT)
    shown = [""]  # the postfix on the bar, set only when it changes

    def update(path_done: float, time_lost: float) -> None:
        raise_if_interrupted()
        if bar is not None:
            text = f"time lost to slowing {time_lost:.2f} s"
            if text != shown[0]:
                shown[0] = text
                bar.set_postfix_str(text, refresh=False)
            bar.update(100.0 * path_done - bar.n)

    return bar, update


def run_experiment(
    exp: Experiment,
    out_dir: str | Path | None = None,
    *,
    progress: bool | None = None,
    plots: bool = True,
    animate: bool = False,
    controller: DualArmController | None = None,
    plant: Plant | None = None,
    figures: FigureWriter | None = None,
) -> RunOutcome:
    """Roll the experiment out and write its outputs.

    Parameters
    ----------
    exp : Experiment
        Built by :func:`~dualarm_qp.experiments.setup.build_experiment`.
    out_dir : path, optional
        Folder for ``summary.json``, ``trajectory.csv``, the PNG plots and
        ``report.html``; nothing is written when None.
    progress : bool, optional
        Show a progress bar; default: when standard error is a terminal.
    plots : bool
        Draw the PNG plots and write ``report.html`` (the page that gathers them).
    animate : bool
        Also write ``animation.html``, the run's 3D animation (:mod:`dualarm_qp.viz`).
    controller : DualArmController, optional
        The controller to run, already built by ``exp.controller()`` (default: built
        here).
    plant : Plant, optional
        What the commands drive (``--plant mujoco``:
        :class:`~dualarm_qp.physics.plant.MujocoPlant`); default: the model itself.
    figures : callable, optional
        What writes the PNG figures, called as ``figures(out, exp)`` once
        ``trajectory.csv`` is written and returning the file names (default:
        :func:`~dualarm_qp.experiments.figures.run_figures.write_run_figures`, in this
        process). The command line passes a
        :class:`~dualarm_qp.experiments.figures.process.FigureProcess`, started before the
        run, which draws them in other processes.

    Returns
    -------
    RunOutcome
        The outputs are written even when the run fails part-way: the summary then
        says ``completed: false`` and why, and the CSV holds the completed samples. A
        KeyboardInterrupt (Ctrl-C) during the rollout stops it the same way (status
        ``interrupted``, criterion ``"interrupted"``); one that comes while the files
        are written is raised once they all are.
    """
    outcome, hold = run_and_write(exp, out_dir, progress=progress, plots=plots,
                                  animate=animate, controller=controller, plant=plant,
                                  figures=figures)
    hold.deliver()
    return outcome


def run_and_write(
    exp: Experiment,
    out_dir: str | Path | None = None,
    *,
    progress: bool | None = None,
    plots: bool = True,
    animate: bool = False,
    controller: DualArmController | None = None,
    plant: Plant | None = None,
    figures: FigureWriter | None = None,
) -> tuple[RunOutcome, SignalHold]:
    """Do what :func:`run_experiment` does, but hand back a signal held while writing.

    For callers that must record the outcome before they stop (a reproduction):
    they call ``hold.deliver()`` when ready.

    Returns
    -------
    outcome : RunOutcome
        As :func:`run_experiment`.
    hold : SignalHold
        ``hold.signum`` is the SIGINT or SIGTERM that came while the files were
        written (None if none did).
    """
    if controller is None:
        controller = exp.controller()
    if progress is None:
        progress = sys.stderr.isatty()
    bar, update = _progress(exp.name, progress)
    t0 = time.perf_counter()
    try:
        result = rollout(controller, exp.initial, duration=exp.duration, project=exp.project,
                         initial_rates=exp.start_rates(),
                         limits=exp.limits, progress=update, stop_on_interrupt=True,
                         plant=plant)
    except BaseException:
        if bar is not None:
            bar.close()
        raise
    wall = time.perf_counter() - t0
    if plant is not None:  # what it measured at the hands, if it does
        record_readings(result.trace, plant)
    with SignalHold(deliver=False) as hold:
        if bar is not None:
            bar.close()
        summary = make_summary(exp, result, wall)
        if plant is not None:
            summary["plant"] = type(plant).__name__
        out = None
        if out_dir is not None:
            out = Path(out_dir)
            write_outputs(out, exp, result, summary, plots=plots, animate=animate,
                          figures=figures)
    return RunOutcome(result, summary, out), hold


def make_summary(exp: Experiment, result: RolloutResult, wall_s: float) -> dict[str, Any]:
    """Return the JSON summary of a run."""
    opts = exp.options
    return {
        "experiment": exp.name,
        "config": exp.path,
        "solver": exp.solver_name,
        "solver_options": exp.solver_options,
        "policy": exp.policy,
        "units": "SI: m, rad, s (converted from the file's units on load)",
        # Where each arm's model came from (SerialArm.source) and its joints.
        "arms": {role: {"source": arm.source, "joints": arm.n,
                        "joint_names": arm.joint_names}
                 for role, arm in (("leader", exp.task.leader),
                                   ("follower", exp.task.follower))},
        "settings": {
            "dt_s": opts.dt,
            "duration_s": exp.duration,
            "grasp_weight_si": opts.grasp_weight,
            "joint_weights": opts.joint_weights.tolist(),
            "velocity_limits": opts.velocity_limits,
            "grasp_speed_max_m_s": opts.grasp_speed_max,
            "correction_gain_1_s": opts.correction_gain,
            "leader_gain_1_s": exp.leader_gain,
            "exact_orientation": opts.exact_orientation,
            "fallback_solver": (exp.fallback if result.hard_bounds
                                and exp.fallback != exp.solver_name else None),
            "centre_horizon_s": opts.centre_horizon,
        },
        "reconstruction": exp.notes,
        "limits_kept": limits_kept(exp, result.hard_bounds),
        "status": run_status(result),
        **result.summary(),
        "wall_time_s": wall_s,
        "python": platform.python_version(),
    }


def remove_run_outputs(out: Path) -> list[str]:
    """Remove the files of an earlier run from ``out``; ``summary.json`` goes first.

    Only the files a run owns (:data:`OUTPUT_FILES` and the temporary files they are
    written through) are removed; anything else in the folder stays.

    Returns
    -------
    list of str
        The names removed.
    """
    first = out / "summary.json"
    removed = ["summary.json"] if first.is_file() else []
    first.unlink(missing_ok=True)
    return removed + remove_owned(out, OUTPUT_FILES)


def write_resolved_config(path: Path, config_file: str) -> bool:
    """Write the experiment file a run was built from, resolved, to ``path`` (YAML).

    The keys the file set, as validated (file units kept), with a URDF ``file`` made
    absolute, so that the copy builds the same scene from any folder.

    Returns
    -------
    bool
        False (nothing written) when ``config_file`` is not a readable experiment file
        (an experiment built in code).
    """
    import yaml

    from ..errors import DualArmError
    from .config import load_config

    source = Path(config_file)
    if not source.is_file():
        return False
    try:
        data = load_config(source).model_dump(mode="json", exclude_unset=True)
    except DualArmError:
        return False
    for role in ("leader", "follower"):
        urdf = data.get(role, {}).get("urdf")
        if isinstance(urdf, dict) and "file" in urdf:
            urdf["file"] = str((source.parent / urdf["file"]).resolve())
    text = (f"# The experiment file of this run ({source}), resolved: its keys as "
            "validated, URDF paths absolute.\n" + yaml.safe_dump(data, sort_keys=False))
    write_text(path, text)
    return True


def _write_run_files(out: Path, exp: Experiment, result: RolloutResult, cols: dict[str, Any],
                     *, animate: bool) -> list[str]:
    """Write ``trajectory.csv`` (columns ``cols``), ``config.yaml`` and the animation."""
    write_trace_csv(out / "trajectory.csv", result.trace, columns=cols)
    written = ["trajectory.csv"]
    if write_resolved_config(out / "config.yaml", exp.path):
        written.append("config.yaml")  # what rebuilds the scene (dualarm-qp animate)
    if animate and len(result.trace):
        from ..viz.animation import ANIMATION_FILE, write_animation

        write_animation(out / ANIMATION_FILE, exp.task, out / "trajectory.csv",
                        title=f"{exp.name} ({exp.solver_name})")
        written.append(ANIMATION_FILE)
    return written


def write_outputs(out: Path, exp: Experiment, result: RolloutResult, summary: dict[str, Any],
                  *, plots: bool = True, animate: bool = False,
                  figures: FigureWriter | None = None,
                  columns: dict[str, Any] | None = None) -> list[str]:
    """Write the output set of a run into ``out``, replacing an earlier run's.

    The earlier run's files go first (:func:`remove_run_outputs`), then
    ``trajectory.csv``, the plots and ``report.html`` are written, each atomically, and
    ``summary.json``
    comes last, its ``outputs`` listing exactly the other files written. An error on the
    way removes what this call wrote (no set without its summary is left). Call it
    inside a :class:`~dualarm_qp._signals.SignalHold` for an all-or-nothing set.
    ``figures`` writes the PNG figures (see :func:`run_experiment`). ``columns`` are
    further columns of ``trajectory.csv`` (a cell's, :mod:`dualarm_qp.cell.record`),
    after the run's own.

    Returns
    -------
    list of str
        The files written, ``summary.json`` last.
    """
    out.mkdir(parents=True, exist_ok=True)
    remove_run_outputs(out)
    try:
        return _write_outputs(out, exp, result, summary, plots=plots, animate=animate,
                              figures=figures, columns=columns)
    except BaseException:
        remove_run_outputs(out)  # a set without its summary is no run: leave none
        raise


def _write_outputs(out: Path, exp: Experiment, result: RolloutResult, summary: dict[str, Any],
                   *, plots: bool, animate: bool, figures: FigureWriter | None = None,
                   columns: dict[str, Any] | None = None) -> list[str]:
    """Write the files of :func:`write_outputs`, ``summary.json`` last.

    A ``figures`` writer that takes the trace ahead (:class:`FiguresAhead`) is sent it
    first and draws while the other files are written; it is closed if one of them
    fails.
    """
    cols = csv_columns(result.trace, columns)
    ahead = (figures if plots and len(result.trace) and isinstance(figures, FiguresAhead)
             else None)
    if ahead is not None:
        from .figures.rundata import RunData

        ahead.submit(out, exp, RunData.from_columns(cols))
    try:
        written = _write_run_files(out, exp, result, cols, animate=animate)
    except BaseException:
        if ahead is not None:
            ahead.close()
        raise
    if plots and len(result.trace):
        from .html_report import REPORT_FILE, write_run_report

        if figures is None:
            from .figures import write_run_figures

            figures = write_run_figures
        pngs = figures(out, exp)
        summary["outputs"] = [*written, *pngs, REPORT_FILE]  # the report shows the list
        write_run_report(out, summary, figures=pngs)
        written += [*pngs, REPORT_FILE]
    summary["outputs"] = list(written)
    write_json(out / "summary.json", summary)
    return [*written, "summary.json"]
