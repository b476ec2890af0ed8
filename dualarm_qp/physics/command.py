"""``dualarm-qp physics RUN_DIR``: check a finished run in MuJoCo, add it to its outputs.

The run's ``config.yaml`` rebuilds its task and its ``physics:`` settings; its
``trajectory.csv`` gives the recorded joints. The rigid replay and the closed loop run
(:mod:`.check`; a run that recorded fewer than two samples has no replay); then
``physics.png`` is drawn, and ``report.html`` and ``summary.json`` (key ``physics``) are
rewritten, ``summary.json`` last, with SIGINT and SIGTERM held.
Nothing is written before both simulations are done; an error while writing puts the
earlier ``report.html`` and ``physics.png`` back (or removes them if there were none),
so the folder is as before.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from pathlib import Path
from typing import Any

from .._io import atomic_write_with, write_json, write_text
from .._signals import SignalHold
from ..errors import DualArmError, InvalidInputError
from ..experiments.animate import read_run_summary, run_config
from ..experiments.config import ExperimentConfig, load_config
from ..experiments.figures.rundata import RunData
from ..experiments.html_report import REPORT_FILE, render_run_report
from ..experiments.setup import Experiment, build_experiment
from ..experiments.setup_checks import check_physics_tau_max
from .check import closed_loop, physics_summary, replay
from .report import PHYSICS_FIGURE, write_physics_figure
from .settings import PhysicsSettings


def settings_of(cfg: ExperimentConfig) -> PhysicsSettings:
    """Return the physics settings of an experiment file (SI)."""
    return PhysicsSettings.from_spec(cfg.physics, 1e-3 if cfg.units.length == "mm" else 1.0,
                                     math.pi / 180.0 if cfg.units.angle == "deg" else 1.0,
                                     1e-3 if cfg.units.time == "ms" else 1.0)


def settings_for(cfg: ExperimentConfig, exp: Experiment, path: str) -> PhysicsSettings:
    """Return the physics settings of the experiment file ``path``, checked against its arms.

    Raises
    ------
    ConfigError
        A ``physics.tau_max.<arm>`` with neither 1 value nor one per joint of the arm.
    """
    # build_experiment checked it too (so that ``run`` refuses it); ``exp`` may be another's.
    check_physics_tau_max(cfg, {"leader": exp.task.leader, "follower": exp.task.follower},
                          path)
    return settings_of(cfg)


def check_run(run_dir: str | Path, *, delay: int | None = None) -> dict[str, Any]:
    """Check the run in ``run_dir`` in MuJoCo; return the ``physics`` section written.

    Parameters
    ----------
    run_dir : path
        A folder written by ``dualarm-qp run`` (``summary.json``, ``trajectory.csv``,
        ``config.yaml``).
    delay : int, optional
        Override the file's ``physics.delay`` (the closed loop this many samples late).

    Raises
    ------
    InvalidInputError
        Not a run folder, or its files cannot give the task.
    ConfigError
        A bad ``physics:`` section.
    PhysicsError
        MuJoCo is missing, refused the model, or the simulation diverged.
    """
    run = Path(run_dir)
    if not run.is_dir():
        raise InvalidInputError(f"{run}: not a folder (RUN_DIR is the output folder of a run)")
    summary = read_run_summary(run)
    config = run_config(run, summary)
    cfg = load_config(config)
    try:
        exp = build_experiment(cfg, str(config))
    except DualArmError as err:
        raise InvalidInputError(f"cannot rebuild the task of {run}: {err}") from None
    settings = settings_for(cfg, exp, str(config))
    if delay is not None:
        settings = dataclasses.replace(settings, delay=int(delay))
    data = RunData.read(run / "trajectory.csv")
    base = None  # a run that stopped before its second sample has nothing to replay
    if len(data) >= 2:
        base = replay(exp, settings, data.col("t"), data.joints("l"), data.joints("f"),
                      data.col("path_t"), data.col("grasp"),
                      data.col("grasp_leader") if data.has("grasp_leader") else None)
    loop = closed_loop(exp, settings)
    physics = physics_summary(loop, base, settings)
    logs = {"closed_loop": loop.log} if base is None else {"replay": base.log,
                                                           "closed_loop": loop.log}
    _write(run, summary, physics, logs)
    return physics


def _write(run: Path, summary: dict[str, Any], physics: dict[str, Any],
           logs: dict[str, Any]) -> None:
    """Write the figure, the report and the summary; on an error, leave the folder as it was."""
    report = run / REPORT_FILE
    old_report = report.read_bytes() if report.is_file() else None
    figure = run / PHYSICS_FIGURE
    old_figure = figure.read_bytes() if figure.is_file() else None  # an earlier check's
    outputs = [str(o) for o in summary.get("outputs", []) if o != "summary.json"]
    new = dict(summary, physics=physics)
    with SignalHold():
        try:
            write_physics_figure(figure, logs, physics)
            if PHYSICS_FIGURE not in outputs:
                outputs.append(PHYSICS_FIGURE)
            if REPORT_FILE not in outputs:
                outputs.append(REPORT_FILE)
            new["outputs"] = outputs
            pngs = [o for o in outputs if o.endswith(".png")]
            write_text(report, render_run_report(run, new, pngs))
            write_json(run / "summary.json", new)
        except BaseException:
            for path, old in ((report, old_report), (figure, old_figure)):
                if old is not None:
                    atomic_write_with(path, functools.partial(_put, data=old))
                else:
                    path.unlink(missing_ok=True)
            raise


def _put(path: str, data: bytes) -> None:
    Path(path).write_bytes(data)


__all__ = ["check_run", "settings_for", "settings_of"]
