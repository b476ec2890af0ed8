"""The animation of a finished run folder (``dualarm-qp animate RUN_DIR``).

The run's ``config.yaml`` (the resolved experiment file it wrote) rebuilds its task; the
recorded ``trajectory.csv`` gives the motion; :func:`dualarm_qp.viz.write_animation`
draws them.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from .._io import write_json
from .._signals import SignalHold
from ..errors import DualArmError, InvalidInputError
from ..viz.animation import ANIMATION_FILE, write_animation
from .config import load_config
from .setup import build_experiment


def read_run_summary(run: Path) -> dict[str, Any]:
    """Return a run folder's ``summary.json``.

    Raises
    ------
    InvalidInputError
        The file is missing, unreadable or not a JSON object.
    """
    path = run / "summary.json"
    try:
        summary = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise InvalidInputError(f"{path}: not found; RUN_DIR must be a folder written by "
                                "'dualarm-qp run' (or a case folder of 'dualarm-qp "
                                "reproduce')") from None
    except (OSError, ValueError) as err:
        raise InvalidInputError(f"{path}: cannot read it: {err}") from None
    if not isinstance(summary, dict):
        raise InvalidInputError(f"{path}: not a run summary (a JSON object expected)")
    return summary


def run_config(run: Path, summary: dict[str, Any]) -> Path:
    """Return the experiment file of a run: its ``config.yaml``, else the file it names.

    Raises
    ------
    InvalidInputError
        Neither exists.
    """
    own = run / "config.yaml"
    if own.is_file():
        return own
    named = summary.get("config")
    if isinstance(named, str) and Path(named).is_file():
        return Path(named)
    if not isinstance(named, str) or named.startswith("<"):
        raise InvalidInputError(
            f"{run}: holds no config.yaml and was not run from an experiment file (its "
            f"summary.json names {named!r}); an animation is built from the file: run the "
            "experiment from its YAML file, or pass the file's path to build_experiment")
    raise InvalidInputError(f"{run}: holds no config.yaml and the experiment file its "
                            f"summary.json names ({named!r}) is gone; rerun the "
                            "experiment to get config.yaml")


def animate_run(run_dir: str | Path, out: str | Path | None = None) -> Path:
    """Write the animation of a finished run.

    Parameters
    ----------
    run_dir : path
        A folder written by ``dualarm-qp run`` (``summary.json``, ``trajectory.csv``,
        ``config.yaml``).
    out : path, optional
        Where to write; default ``run_dir/animation.html``, which is then added to the
        outputs that the run's ``summary.json`` lists.

    Returns
    -------
    Path
        The file written.

    Raises
    ------
    InvalidInputError
        Not a run folder, or its files cannot give the scene.
    """
    run = Path(run_dir)
    if not run.is_dir():
        raise InvalidInputError(f"{run}: not a folder (RUN_DIR is the output folder of a run)")
    summary = read_run_summary(run)
    config = run_config(run, summary)
    try:
        exp = build_experiment(load_config(config), str(config))
    except DualArmError as err:
        raise InvalidInputError(f"cannot rebuild the scene of {run}: {err}") from None
    title = f"{summary.get('experiment', exp.name)} ({summary.get('solver', exp.solver_name)})"
    target = Path(out) if out is not None else run / ANIMATION_FILE
    with SignalHold():  # the file and the summary's list of outputs change together
        write_animation(target, exp.task, run / "trajectory.csv", title=title)
        outputs = summary.get("outputs")
        if out is None and isinstance(outputs, list) and ANIMATION_FILE not in outputs:
            summary["outputs"] = [*outputs, ANIMATION_FILE]
            write_json(run / "summary.json", summary)
    return target


__all__ = ["animate_run", "read_run_summary", "run_config"]
