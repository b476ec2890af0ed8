"""Run an experiment and write its outputs (CSV, JSON, PNG)."""

from __future__ import annotations

import platform
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..control.rollout import RolloutResult, rollout
from .outputs import write_json, write_trace_csv
from .plots import plot_closure, plot_grasp, plot_joints
from .setup import Experiment

OUTPUT_FILES = ("summary.json", "trajectory.csv", "joints.png", "grasp.png", "closure.png")


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


def _progress_bar(total: int, label: str) -> tuple[Any, Any]:
    from tqdm import tqdm

    bar = tqdm(total=total, desc=label, unit="step", leave=False, file=sys.stderr)

    def update(done: int, _total: int) -> None:
        bar.update(done - bar.n)

    return bar, update


def run_experiment(
    exp: Experiment,
    out_dir: str | Path | None = None,
    *,
    progress: bool | None = None,
    plots: bool = True,
) -> RunOutcome:
    """Roll the experiment out and write its outputs.

    Parameters
    ----------
    exp : Experiment
        Built by :func:`~dualarm_qp.experiments.setup.build_experiment`.
    out_dir : path, optional
        Folder for ``summary.json``, ``trajectory.csv`` and the PNG plots; nothing is
        written when None.
    progress : bool, optional
        Show a progress bar; default: when standard error is a terminal.
    plots : bool
        Draw the PNG plots.

    Returns
    -------
    RunOutcome
        The outputs are written even when the run fails part-way: the summary then
        says ``completed: false`` and why, and the CSV holds the completed samples.
    """
    controller = exp.controller()
    if progress is None:
        progress = sys.stderr.isatty()
    steps = int(exp.duration / exp.options.dt + 1e-9) + 1
    bar, update = _progress_bar(steps, exp.name) if progress else (None, None)
    t0 = time.perf_counter()
    try:
        result = rollout(controller, exp.initial, duration=exp.duration, project=exp.project,
                         limits=exp.limits, progress=update)
    finally:
        if bar is not None:
            bar.close()
    wall = time.perf_counter() - t0
    summary = make_summary(exp, result, wall)
    out = None
    if out_dir is not None:
        out = Path(out_dir)
        write_outputs(out, exp, result, summary, plots=plots)
    return RunOutcome(result, summary, out)


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
            "fallback_solver": exp.fallback if result.hard_bounds else None,
            "centre_horizon_s": opts.centre_horizon,
        },
        "reconstruction": exp.notes,
        **result.summary(),
        "wall_time_s": wall_s,
        "python": platform.python_version(),
    }


def write_outputs(out: Path, exp: Experiment, result: RolloutResult, summary: dict[str, Any],
                  *, plots: bool = True) -> None:
    """Write every output file of a run into ``out`` (each file atomically)."""
    out.mkdir(parents=True, exist_ok=True)
    write_trace_csv(out / "trajectory.csv", result.trace)
    if plots and len(result.trace):
        task = exp.task
        tag = f"{exp.name} ({exp.solver_name})"
        plot_joints(out / "joints.png", result.trace, task.leader, task.follower, title=tag)
        plot_grasp(out / "grasp.png", result.trace, task.surface, title=tag)
        plot_closure(out / "closure.png", result.trace, title=tag)
    summary["outputs"] = [name for name in OUTPUT_FILES if (out / name).exists()]
    write_json(out / "summary.json", summary)
