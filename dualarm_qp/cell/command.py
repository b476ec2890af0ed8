"""``dualarm-qp drive``: run a cell from an experiment file and write the run's folder.

The folder is the one ``dualarm-qp run`` writes (``trajectory.csv`` with the cell's
columns after the run's, ``summary.json`` with a ``cell`` section, the plots,
``report.html``, ``config.yaml``), so ``animate``, ``physics`` and ``bag`` read a
hardware log as they read a simulated run.

The parser's part (:func:`add_parsers`) imports nothing heavy: the experiment's schema,
NumPy and the cells are imported by the functions that run a command.
"""

from __future__ import annotations

import argparse
import dataclasses
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .._signals import SignalHold, raise_if_interrupted
from ..bag.topics import DEFAULT_PORT

if TYPE_CHECKING:
    from ..experiments.config import ExperimentConfig
    from ..experiments.experiment import Experiment
    from .base import Cell
    from .loop import DriveResult, DriveSettings, Observer

#: The cells ``drive --cell`` knows.
CELLS = ("mujoco", "franka", "ros2")

#: The watchdog's default: this many samples of ``dt``.
WATCHDOG_SAMPLES = 3


def drive_settings(cfg: ExperimentConfig, exp: Experiment, *, dry_run: bool) -> DriveSettings:
    """Return the loop's guards from the file's ``cell:`` section, in SI."""
    from ..experiments.config import ANGLE_SCALE, TIME_SCALE
    from .loop import DriveSettings

    c = cfg.cell
    angle, t = ANGLE_SCALE[cfg.units.angle], TIME_SCALE[cfg.units.time]
    dt = exp.options.dt
    return DriveSettings(
        watchdog=WATCHDOG_SAMPLES * dt if c.watchdog is None else c.watchdog * t,
        dry_run=dry_run,
        start_tolerance=0.01 if c.start_tolerance is None else c.start_tolerance * angle,
        range_margin=c.range_margin * angle)


def commanded(exp: Experiment, headroom: float) -> Experiment:
    """Return the experiment a cell's controller runs: the arms' limits with headroom.

    Every joint's speed, acceleration and jerk limit is multiplied by ``1 - headroom``
    (the step and the clamp keep those); the recorded motion is still judged against the
    file's. The servos' tracking error (a lag, friction, the arms' coupling) has the rest.
    """
    if headroom == 0.0:
        return exp
    keep = 1.0 - headroom
    leader, follower = (arm.with_limits(qd_max=arm.qd_max * keep, qdd_max=arm.qdd_max * keep,
                                        qddd_max=arm.qddd_max * keep)
                        for arm in (exp.task.leader, exp.task.follower))
    task = dataclasses.replace(exp.task, leader=leader, follower=follower)
    return dataclasses.replace(exp, task=task)


def check_drivable(exp: Experiment, path: str) -> None:
    """Refuse a task whose grasp the cell cannot estimate from the joints.

    Raises
    ------
    CellSetupError
        A sliding leader grasp, or a supporting follower (Case 2).
    """
    from .base import CellSetupError

    if exp.task.leader_surface is not None:
        raise CellSetupError(f"{path}: object.leader_surface: a cell needs the leader to "
                             "grasp rigidly (the object's pose is read from the leader's "
                             "hand; docs/robots.md)")
    if exp.task.contact is not None:
        raise CellSetupError(f"{path}: object.support: a cell drives a follower that grasps "
                             "the object (Case 1), not one that supports it")


def open_cell(kind: str, cfg: ExperimentConfig, exp: Experiment, path: str, *,
              dry_run: bool = False) -> Cell:
    """Build the cell ``kind`` of the experiment (not yet opened; ``dry_run``: it sends nothing).

    Raises
    ------
    CellSetupError
        An unknown kind, or a ``cell:`` section the back-end cannot use.
    """
    from .base import CellSetupError

    if kind == "mujoco":
        from ..physics.check import arm_tau_max
        from ..physics.command import settings_for
        from ..physics.plant import MujocoPlant
        from .mujoco import MujocoCell

        plant = MujocoPlant(exp.task, settings_for(cfg, exp, path), arm_tau_max=arm_tau_max(exp))
        return MujocoCell(plant, exp.initial, exp.options.dt, realtime=cfg.cell.realtime)
    if kind == "franka":
        from .franka import franka_cell

        return franka_cell(cfg, exp, path, drive_settings(cfg, exp, dry_run=False).watchdog)
    if kind == "ros2":
        from .ros2 import ros2_cell

        return ros2_cell(cfg, exp, path, dry_run=dry_run)
    raise CellSetupError(f"unknown cell {kind!r}; the cells are {', '.join(CELLS)}")


def drive_and_write(exp: Experiment, cfg: ExperimentConfig, cell: Cell, out: Path | None, *,
                    dry_run: bool = False, plots: bool = True,
                    observer: Observer | None = None) -> tuple[DriveResult, dict[str, Any]]:
    """Drive ``cell`` and write the run's folder (with SIGINT and SIGTERM held).

    ``observer`` is handed each recorded sample (a live view: :mod:`dualarm_qp.bag.live`).

    Returns
    -------
    result : DriveResult
        What the loop did.
    summary : dict
        The content of ``summary.json``.
    """
    from ..experiments.run import make_summary, write_outputs
    from .loop import drive

    settings = drive_settings(cfg, exp, dry_run=dry_run)
    controller = commanded(exp, cfg.cell.headroom).controller()

    def progress(done: float, lost: float) -> None:
        raise_if_interrupted()

    t0 = time.perf_counter()
    res = drive(cell, controller, exp.initial, duration=exp.duration, settings=settings,
                limits=exp.limits, progress=progress, judged_by=exp.task, observer=observer)
    wall = time.perf_counter() - t0
    with SignalHold():
        summary = make_summary(exp, res.result, wall)
        summary["cell"] = res.cell
        summary["plant"] = type(cell).__name__
        if out is not None:
            write_outputs(out, exp, res.result, summary, plots=plots, columns=res.columns)
    return res, summary


def _together(observers: list[Observer]) -> Observer | None:
    """One observer that calls each of ``observers`` in turn (None: there are none)."""
    if not observers:
        return None
    if len(observers) == 1:
        return observers[0]

    def each(trace: Any, k: int) -> None:
        for observer in observers:
            observer(trace, k)

    return each


def cmd_drive(args: argparse.Namespace) -> int:
    """``dualarm-qp drive``: exit 0 completed, 1 failed or stopped, 130 interrupted."""
    from ..cli_commands import EXIT_FAILED, EXIT_INTERRUPTED, EXIT_OK, output_folder, print_error
    from ..experiments.config import load_config, safe_name
    from ..experiments.outputs import check_unused_folder
    from ..experiments.run import OUTPUT_FILES
    from ..experiments.setup import build_experiment
    from .base import CellSetupError

    path = str(args.config)
    cfg = load_config(args.config)
    exp = build_experiment(cfg, path)
    check_drivable(exp, path)
    exp.controller()  # fail early (exit 2) on an unknown or missing solver
    if args.send_run is not None:
        if args.cell != "ros2":
            raise CellSetupError("--send-run sends a run to ROS 2 trajectory controllers: "
                                 "give --cell ros2")
        from .ros2_trajectory import cmd_send_run

        return cmd_send_run(args, cfg, exp, path, drive_settings(cfg, exp, dry_run=False))
    cell = open_cell(args.cell, cfg, exp, path, dry_run=args.dry_run)
    out = Path(args.out if args.out else Path("runs") / safe_name(exp.name)
               / f"cell_{args.cell}")
    check_unused_folder(out, force=args.force, what="a drive", names=OUTPUT_FILES)
    out = output_folder(out)
    view = None
    if args.foxglove:
        from ..bag.live import open_drive_view

        view = open_drive_view(cfg, exp, path, port=args.port)
        print(f"live view at {view.view.url} (Foxglove WebSocket)", flush=True)
    observers = [o for o in (view, getattr(cell, "observe", None)) if o is not None]
    try:
        res, summary = drive_and_write(exp, cfg, cell, out, dry_run=args.dry_run,
                                       plots=not args.no_plots,
                                       observer=_together(observers))
    finally:
        if view is not None:
            view.view.close()
    stop = summary["cell"]["stop"]
    print(f"{exp.name}: cell {args.cell}{' (dry run)' if args.dry_run else ''}: "
          f"{summary['status']}, {summary['samples']} samples, "
          f"{summary['path_completed_pct']:.1f}% of the path; closure error max "
          f"{summary['closure_pos_err_max_m'] * 1e3:.3g} mm; stopped ({stop['reason']}) in "
          f"{stop['samples']} samples, at rest: {stop['at_rest']}")
    print(f"  outputs: {out}/")
    if summary["status"] == "interrupted":
        print_error(f"{summary['message']}; the arms were brought to rest and the samples "
                    "are written")
        return EXIT_INTERRUPTED
    if not res.result.completed:
        print_error(summary["message"])
        return EXIT_FAILED
    return EXIT_OK


def add_parsers(sub: Any) -> None:
    """Add ``drive`` and ``serve`` to the command line's subcommands."""
    d = sub.add_parser("drive", help="drive two arms along the file's path through a cell; "
                       "write the same folder as 'run'")
    d.add_argument("config", type=Path, help="experiment YAML file (with a cell: section "
                   "for ROS 2 and Franka)")
    d.add_argument("--cell", choices=CELLS, default="mujoco", help="the cell (default mujoco)")
    d.add_argument("--dry-run", action="store_true",
                   help="read the robots and compute the commands, send nothing")
    d.add_argument("--out", help="output folder (default runs/<name>/cell_<cell>)")
    d.add_argument("--no-plots", action="store_true", help="skip the PNG plots")
    d.add_argument("--force", action="store_true",
                   help="write into a folder that holds other files, keeping them")
    d.add_argument("--send-run", nargs="?", const="rollout", metavar="RUN_DIR",
                   help="ROS 2: send a completed run (RUN_DIR, or without it a fresh rollout "
                   "of the file) whole to each arm's joint_trajectory_controller, then watch")
    d.add_argument("--foxglove", action="store_true",
                   help="serve each sample live on 127.0.0.1 (Foxglove WebSocket), as "
                   "'bag' writes it")
    d.add_argument("--port", type=int, default=DEFAULT_PORT,
                   help=f"the live view's port (default {DEFAULT_PORT}; 0: any free one)")
    d.set_defaults(func=cmd_drive)
    from .serve import add_serve_parser

    add_serve_parser(sub)


__all__ = ["CELLS", "WATCHDOG_SAMPLES", "add_parsers", "check_drivable", "cmd_drive", "commanded",
           "drive_and_write", "drive_settings", "open_cell"]
