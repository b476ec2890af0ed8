"""Command-line interface of ``dualarm-qp``.

Commands: run, animate, physics, reproduce, collisions, bench, sweep, sweep-report,
solvers, drive, serve, bag.

Exit codes: 0 success, 1 the run failed (what it completed is still written), 2 bad
input (configuration, arguments, missing solver, an output folder in use), 130
interrupted by Ctrl-C (SIGINT) or SIGTERM (what was done is written, marked
``interrupted``), 141 standard output closed early (``dualarm-qp solvers | head -1``).
For ``physics``, 1 is a verdict other than ``ok`` (the check's outputs are written) or
a simulation that diverged. What each command does is in :mod:`dualarm_qp.cli_commands`.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
import traceback
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

from . import __version__
from ._signals import InterruptHandlers, interrupt_requested
from .cli_commands import (
    EXIT_BAD_INPUT,
    EXIT_BROKEN_PIPE,
    EXIT_FAILED,
    EXIT_INTERRUPTED,
    EXIT_OK,
    cmd_animate,
    cmd_bench,
    cmd_collisions,
    cmd_physics,
    cmd_reproduce,
    cmd_run,
    cmd_solvers,
    cmd_sweep,
    cmd_sweep_report,
    print_error,
)
from .errors import DualArmError


def build_parser() -> argparse.ArgumentParser:
    """Build the argument parser (exposed for documentation and tests).

    It imports nothing heavy (no NumPy, Pinocchio, Coal, YAML reader or matplotlib):
    each command imports what it uses when it runs, so that ``run`` can fork its drawing
    process first (:mod:`dualarm_qp.experiments.figures.process`).
    """
    p = argparse.ArgumentParser(
        prog="dualarm-qp",
        description="Coordinate two arms carrying one object with a sliding follower grasp "
                    "(Suh & Shin 1988): run experiments, reproduce the paper, compare solvers.",
    )
    p.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    p.add_argument("--debug", action="store_true", help="show tracebacks of internal errors")
    sub = p.add_subparsers(dest="command", metavar="COMMAND")
    _add_run(sub)
    _add_animate(sub)
    _add_physics(sub)
    _add_reproduce(sub)
    _add_collisions(sub)
    _add_bench(sub)
    _add_sweep(sub)
    _add_sweep_report(sub)
    _add_solvers(sub)
    from .cell.command import add_parsers  # drive and serve (docs/robots.md)

    add_parsers(sub)
    from .bag.command import add_bag_parser  # bag (docs/ros2.md)

    add_bag_parser(sub)
    for command in sub.choices.values():  # --debug after the command too
        command.add_argument("--debug", action="store_true", default=argparse.SUPPRESS,
                             help="show tracebacks of internal errors")
    return p


def _add_run(sub: Any) -> None:
    """Add the command for one experiment from a YAML file."""
    r = sub.add_parser("run", help="run one experiment from a YAML file")
    r.add_argument("config", type=Path, help="experiment YAML file")
    r.add_argument("--solver", help="override the file's solver (see 'dualarm-qp solvers')")
    r.add_argument("--solver-option", action="append", default=[],
                   metavar="SOLVER.OPTION=VALUE",
                   help="an option for one solver, e.g. qp:osqp.eps_abs=1e-9 (repeatable; "
                        "the value is read as in YAML); the file's solver.options apply "
                        "only to the file's own solver")
    r.add_argument("--out", help="output folder (default runs/<name>/<solver>)")
    r.add_argument("--no-plots", action="store_true", help="skip the PNG plots")
    r.add_argument("--force", action="store_true",
                   help="write into a folder that holds files: replace the files a run "
                        "writes, keep the others")
    r.add_argument("--quiet", action="store_true", help="no progress bar")
    r.add_argument("--animate", action="store_true",
                   help="also write animation.html, a 3D animation of the run that opens "
                        "offline in a web browser")
    r.add_argument("--plant", choices=("model", "mujoco"), default="model",
                   help="what the commands drive: the model itself (default) or a MuJoCo "
                        "simulation with joint servos (needs the [physics] extra; "
                        "docs/physics.md)")
    r.set_defaults(func=cmd_run)


def _add_animate(sub: Any) -> None:
    """Add the command for the animation of a finished run."""
    a = sub.add_parser("animate", help="write the 3D animation (animation.html) of a "
                                       "finished run")
    a.add_argument("run_dir", type=Path, metavar="RUN_DIR",
                   help="output folder of 'dualarm-qp run' (or a case folder of a "
                        "reproduction)")
    a.add_argument("--out", type=Path, default=None,
                   help="file to write (default RUN_DIR/animation.html, then listed in the "
                        "run's summary.json)")
    a.set_defaults(func=cmd_animate)


def _add_physics(sub: Any) -> None:
    """Add the command for the MuJoCo check of a finished run."""
    ph = sub.add_parser("physics", help="check a finished run in MuJoCo: rigid replay and "
                                        "closed loop, with a verdict (docs/physics.md)")
    ph.add_argument("run_dir", type=Path, metavar="RUN_DIR",
                    help="output folder of 'dualarm-qp run'")
    ph.add_argument("--delay", nargs="?", const=1, default=None, type=_samples,
                    metavar="N", help="closed loop N samples late (1 when N is left out; "
                    "overrides the file's physics.delay)")
    ph.set_defaults(func=cmd_physics)


def _samples(text: str) -> int:
    """Return ``--delay``'s number of samples (>= 0)."""
    try:
        value = int(text)
    except ValueError:
        value = -1
    if value < 0:
        raise argparse.ArgumentTypeError(f"a whole number of samples >= 0, not {text!r}")
    return value


def _add_reproduce(sub: Any) -> None:
    """Add the command for the paper's cases."""
    rp = sub.add_parser("reproduce", help="run the paper's three PUMA beam cases and the "
                        "same task with hard limits, draw Figs. 5-6; report.html leads "
                        "to each case")
    rp.add_argument("--out", default="reproduction", help="output folder (default reproduction)")
    rp.add_argument("--configs", type=Path, default=None,
                    help="folder with the three YAML files (default: the bundled copies)")
    rp.add_argument("--quiet", action="store_true", help="no progress bar")
    rp.add_argument("--force", action="store_true",
                    help="write into a folder that holds other files, keeping them (an "
                         "earlier reproduction there is replaced even without --force)")
    rp.set_defaults(func=cmd_reproduce)


def _add_collisions(sub: Any) -> None:
    """Add the command for a file with and without collision avoidance."""
    c = sub.add_parser("collisions", help="run a file with a collision scene with collision "
                       "avoidance, without it and with the fixed grasp; draw the clearances "
                       "and the grasp travel")
    c.add_argument("config", type=Path, help="experiment YAML file with a collision scene "
                   "(obstacles, an object shape)")
    c.add_argument("--out", help="output folder (default runs/<name>/collisions)")
    c.add_argument("--no-plots", action="store_true",
                   help="skip each run's own PNG plots and report.html (collisions.png is "
                        "always drawn)")
    c.add_argument("--animate", action="store_true",
                   help="also write each run's animation.html")
    c.add_argument("--expect-penetration", action="store_true",
                   help="also claim that both runs without avoidance penetrate (the pillar "
                        "demo's story; exit 1 if one does not); otherwise that is measured "
                        "only")
    c.add_argument("--quiet", action="store_true", help="no progress bar")
    c.add_argument("--force", action="store_true",
                   help="write into a folder that holds other files, keeping them (an "
                        "earlier comparison there is replaced even without --force)")
    c.set_defaults(func=cmd_collisions)


def _add_bench(sub: Any) -> None:
    """Add the command for every config with every solver."""
    b = sub.add_parser("bench", help="run every config with every solver, compare them")
    b.add_argument("configs", nargs="*", type=Path, metavar="CONFIG",
                   help="experiment YAML files (default: the beam with speed limits and "
                        "the curved bar)")
    b.add_argument("--solvers", help="comma-separated solver names (default: all available)")
    b.add_argument("--solver-option", action="append", default=[],
                   metavar="SOLVER.OPTION=VALUE",
                   help="an option for one of the solvers, e.g. qp:osqp.eps_abs=1e-9 "
                        "(repeatable); a file's solver.options apply only to its own solver")
    b.add_argument("--out", default="bench_out", help="output folder (default bench_out); "
                   "finished jobs stored there are reused, so a bench resumes; benches "
                   "sharing it split the jobs")
    b.add_argument("--repeat", type=int, default=1,
                   help="rollouts per job; their step timings are pooled (default 1)")
    b.add_argument("--duration", type=float, default=None,
                   help="override every config's run length [s] (e.g. for a quick check)")
    b.add_argument("--no-plots", action="store_true", help="skip bench.png")
    b.add_argument("--quiet", action="store_true", help="no per-job progress lines")
    b.set_defaults(func=cmd_bench)


def _add_sweep(sub: Any) -> None:
    """Add the command for an experiment over a grid or sample of its settings."""
    w = sub.add_parser("sweep", help="run an experiment over a grid or random sample of its "
                       "settings on Dask; write a results table and maps")
    w.add_argument("sweep", type=Path, metavar="SWEEP",
                   help="sweep YAML file: a base experiment and the keys to vary "
                        "(docs/sweeps.md)")
    w.add_argument("--out", required=True,
                   help="sweep folder; points stored there are reused, so a sweep resumes")
    where = w.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, default=None,
                       help="worker processes of the embedded Dask cluster (default: one "
                            "per core)")
    where.add_argument("--scheduler", metavar="ADDRESS",
                       help="use a running Dask scheduler, e.g. tcp://host:8786")
    w.add_argument("--batch", type=int, default=None, help=argparse.SUPPRESS)
    w.add_argument("--quiet", action="store_true", help="no progress bar")
    w.set_defaults(func=cmd_sweep)


def _add_sweep_report(sub: Any) -> None:
    """Add the command for the maps of a sweep folder."""
    wr = sub.add_parser("sweep-report", help="draw the maps of a sweep folder into "
                        "report.html (also done at the end of 'sweep')")
    wr.add_argument("dir", metavar="DIR", help="the sweep's --out folder")
    wr.set_defaults(func=cmd_sweep_report)


def _add_solvers(sub: Any) -> None:
    """Add the command for the list of solvers."""
    s = sub.add_parser("solvers", help="list the solvers and whether they are installed")
    s.set_defaults(func=cmd_solvers)


def _drop_stdout() -> None:
    """Point standard output at the null device, so that the final flush is quiet."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError):  # not a real file (captured): nothing to flush later
        pass


@contextlib.contextmanager
def _quiet_swallowed_interrupts() -> Iterator[None]:
    """Print nothing for a KeyboardInterrupt that Python could only ignore.

    One raised inside a weak-reference callback or a finaliser is printed as
    "Exception ignored in ..." and dropped; the interrupt handlers have recorded it,
    and the command stops on it (:func:`~dualarm_qp._signals.interrupt_requested`).
    """
    previous = sys.unraisablehook

    def hook(unraisable: Any) -> None:
        if not isinstance(unraisable.exc_value, KeyboardInterrupt):
            previous(unraisable)

    sys.unraisablehook = hook
    try:
        yield
    finally:
        sys.unraisablehook = previous


def _run_command(args: argparse.Namespace) -> int:
    """Run the command and map what happened to an exit code and one message.

    An error that came after an interrupt (an import cut short, say) is reported as the
    interrupt, with the error named on the same line: it may be the interrupt's doing, or
    a fault of its own that would otherwise go unseen.
    """
    after = ""
    try:
        code = int(args.func(args))
        sys.stdout.flush()  # a closed pipe shows here, not in the flush at exit
    except BrokenPipeError:  # e.g. `dualarm-qp solvers | head -1`: end quietly
        _drop_stdout()
        return EXIT_BROKEN_PIPE
    except KeyboardInterrupt as stop:
        print_error(f"interrupted ({stop})" if str(stop) else "interrupted")
        return EXIT_INTERRUPTED
    except DualArmError as err:
        if interrupt_requested() is None:
            print_error(str(err))
            return EXIT_BAD_INPUT
        code = EXIT_FAILED  # came from the interrupt: reported below
    except Exception as err:
        if args.debug:
            traceback.print_exc()
        if interrupt_requested() is None:  # an internal error: say so plainly, no traceback
            print_error(f"internal error: {type(err).__name__}: {err} "
                        "(rerun with --debug for details)")
            return EXIT_FAILED
        code = EXIT_FAILED  # after the interrupt: reported below, the error named
        after = (f"; then {type(err).__name__}: {err}"
                 + ("" if args.debug else " (rerun with --debug for details)"))
    stopped = interrupt_requested()
    if stopped is not None and code != EXIT_INTERRUPTED:
        print_error(f"interrupted ({stopped}){after}")
        return EXIT_INTERRUPTED
    return code


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``dualarm-qp`` command.

    Parameters
    ----------
    argv : sequence of str, optional
        The arguments; default: the program's (``sys.argv[1:]``). Without them, main
        is the program: after the command, SIGINT and SIGTERM are left at their
        default action, so that a late one ends the process quietly.

    Returns
    -------
    int
        The exit code (see the module docstring).
    """
    parser = build_parser()
    args = parser.parse_args(argv)
    if getattr(args, "func", None) is None:
        parser.print_help()
        return EXIT_BAD_INPUT
    # SIGTERM stops a run the way Ctrl-C does; both are remembered even if swallowed.
    try:
        with InterruptHandlers(final=argv is None), _quiet_swallowed_interrupts():
            return _run_command(args)
    except KeyboardInterrupt:  # another one while the first was being reported
        return EXIT_INTERRUPTED


__all__ = ["EXIT_BAD_INPUT", "EXIT_BROKEN_PIPE", "EXIT_FAILED", "EXIT_INTERRUPTED", "EXIT_OK",
           "build_parser", "main"]


if __name__ == "__main__":
    sys.exit(main())
