"""Command-line interface of ``dualarm-qp``.

Commands: run, animate, physics, reproduce, collisions, bench, sweep, sweep-report,
solvers.

Exit codes: 0 success, 1 the run failed (what it completed is still written), 2 bad
input (configuration, arguments, missing solver, an output folder in use), 130
interrupted by Ctrl-C (SIGINT) or SIGTERM (what was done is written, marked
``interrupted``), 141 standard output closed early (``dualarm-qp solvers | head -1``).
For ``physics``, 1 is a verdict other than ``ok`` (the check's outputs are written) or
a simulation that diverged.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
import tempfile
import traceback
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

from . import __version__
from ._signals import InterruptHandlers, SignalHold, interrupt_requested
from .errors import DualArmError, InvalidInputError

EXIT_OK, EXIT_FAILED, EXIT_BAD_INPUT = 0, 1, 2
EXIT_INTERRUPTED, EXIT_BROKEN_PIPE = 130, 141  # 128 + SIGINT, 128 + SIGPIPE


def _err(msg: str) -> None:
    print(f"dualarm-qp: error: {msg}", file=sys.stderr)


def _output_folder(path: str | Path) -> Path:
    """Create the output folder, or say plainly why it cannot be (bad input, exit 2)."""
    out = Path(path)
    try:
        out.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=out):  # nameless where it can be: never left over
            pass
    except OSError as err:
        reason = err.strerror or str(err)
        if isinstance(err, (FileExistsError, NotADirectoryError)):
            reason = "a file is in the way"
        raise InvalidInputError(f"cannot write the output folder {out}: {reason}") from None
    return out


def _cmd_run(args: argparse.Namespace) -> int:
    from .experiments.config import load_config, safe_name
    from .experiments.options import check_solver_options, parse_solver_options
    from .experiments.outputs import check_unused_folder
    from .experiments.run import OUTPUT_FILES, run_experiment
    from .experiments.setup import build_experiment

    solver_options = parse_solver_options(args.solver_option)
    exp = build_experiment(load_config(args.config), str(args.config), solver=args.solver,
                           solver_options=solver_options)
    check_solver_options(solver_options, used=[exp.solver_name])
    controller = exp.controller()  # fail early (exit 2) on an unknown or missing solver
    plant = None
    blown_up: tuple[type[DualArmError], ...] = ()  # what fails the run rather than the input
    if args.plant == "mujoco":  # docs/physics.md
        from .physics.check import arm_tau_max
        from .physics.command import settings_for
        from .physics.plant import DivergedError, MujocoPlant

        blown_up = (DivergedError,)
        from .physics.compliant import compliant_experiment

        plant = MujocoPlant(exp.task, settings_for(load_config(args.config), exp,
                                                   str(args.config)),
                            arm_tau_max=arm_tau_max(exp))
        if plant.settings.compliance is not None:  # the compliant follower's step
            exp = compliant_experiment(exp, plant)
            controller = exp.controller()
    out = Path(args.out if args.out else Path("runs") / safe_name(exp.name)
               / exp.solver_name.replace(":", "_"))
    check_unused_folder(out, force=args.force, what="a run", names=OUTPUT_FILES)
    new_folder = not out.exists()
    out = _output_folder(out)
    try:
        outcome = run_experiment(exp, out, progress=None if not args.quiet else False,
                                 plots=not args.no_plots, animate=args.animate,
                                 controller=controller, plant=plant)
    except blown_up as err:  # the simulation blew up: a failed run, not bad input
        if new_folder and not any(out.iterdir()):
            out.rmdir()  # nothing was written: leave no empty folder
        _err(str(err))
        return EXIT_FAILED
    print_run_summary(outcome.summary, str(out))
    if outcome.interrupted:
        _err(f"{outcome.summary['message']}; the samples done are written")
        return EXIT_INTERRUPTED
    if not outcome.ok:
        _err(outcome.summary["message"])
        return EXIT_FAILED
    return EXIT_OK


def _clearance_line(r: dict[str, Any]) -> str:
    """Return the console line of ``realised_limits.clearance`` (the smallest distance)."""
    d = r["min_m"]
    smallest = ("no pair" if d is None
                else f"{d * 1e3:.1f} mm ({r['pair']}, sample {r['sample']})")
    rule = (f"safety distance {r['safety_distance_m'] * 1e3:.3g} mm "
            f"{'kept' if r['kept'] else 'NOT KEPT'} (allowance {r['allowance_m'] * 1e3:.3g} mm)"
            if r["enforced"] else "measured only (collision avoidance off)")
    return (f"    {'clearance':<12} smallest {smallest}; {rule}"
            + ("; PENETRATION" if r["penetration"] else ""))


def _torque_line(r: dict[str, Any]) -> str:
    """Return the console line of ``realised_limits.torque`` (the largest share of a limit)."""
    ratio = r["ratio_max"]
    worst = ("no limit known" if ratio is None or ratio != ratio
             else f"{ratio:.3g} ({r['worst_joint']}, {r['torque_at_worst_N_m']:.4g} N m, "
                  f"sample {r['worst_sample']})")
    rule = (f"limits {'kept' if r['kept'] else 'NOT KEPT'} (allowance "
            f"{100 * r['allowance_rtol']:g}%)" if r["enforced"]
            else "measured only (torque limits off)")
    return f"    {'torque':<12} {worst}; {rule}"


def print_run_summary(s: dict[str, Any], out: str) -> None:
    """Print the console summary of one run (from its summary.json content)."""
    from .experiments.limits_kept import limits_lines

    status = s.get("status", "completed" if s["completed"] else "failed")
    print(f"{s['experiment']}: solver {s['solver']}, {s['samples']} samples, "
          f"{status if status == 'completed' else status.upper()}")
    if "limits_kept" in s:
        print("\n".join(limits_lines(s["limits_kept"])))
    if not s["samples"]:  # refused before the first sample: there is nothing to sum up
        failure = s.get("failure") or {}
        print(f"  no sample was run; failed on: {failure.get('criterion', '?')}")
        print(f"  outputs: {out}")
        return
    print(f"  path completed: {s['path_completed_pct']:.1f}%; time lost to scaling: "
          f"{s['time_lost_to_scaling_s'] + 0.0:.3g} s")
    print(f"  leader tracking error max: {s['leader_pos_err_max_m']:.3g} m, "
          f"{s['leader_rot_err_max_rad']:.3g} rad; closure error max: "
          f"{s['closure_pos_err_max_m']:.3g} m, {s['closure_rot_err_max_rad']:.3g} rad")
    limits = ("hard limits: a variable that starts outside may not move further out"
              if s["hard_limits"] else "limits not enforced by this solver")
    print(f"  realised motion, worst share of each limit, above 1 is outside ({limits}):")
    for part, r in s["realised_limits"].items():
        if part == "clearance":  # a distance, not a share of a limit
            print(_clearance_line(r))
            continue
        if part == "torque":  # joint torques, not positions
            print(_torque_line(r))
            continue
        start = r["range_ratio_start"]
        started = (f"; started outside, at {start:.3g}"
                   if start is not None and start > 1.0 else "")
        speed = r["speed_ratio_max"]
        speed_text = ("n/a (no limit)" if speed is None or speed != speed
                      else f"{speed:.3g} ({r['worst_speed']})")
        accel = r.get("acceleration_ratio_max")
        accel_text = ("" if accel is None or accel != accel
                      else f", acceleration {accel:.3g} ({r['worst_acceleration']})")
        print(f"    {part:<12} range {r['range_ratio_max']:.3g} ({r['worst_range']}{started}), "
              f"speed {speed_text}{accel_text}")
    lead = s.get("grasp_leader_start_m")
    lead_text = (f" (leader's {lead * 1e3:.1f} -> {s['grasp_leader_end_m'] * 1e3:.1f} mm)"
                 if isinstance(lead, float) and lead == lead else "")
    print(f"  grasp: {s['grasp_start_m'] * 1e3:.1f} -> {s['grasp_end_m'] * 1e3:.1f} mm"
          f"{lead_text}; "
          f"smallest singular value: leader {s['sigma_min']['leader']:.3g}, "
          f"follower {s['sigma_min']['follower']:.3g}")
    fallback = f", {s['fallback_steps']} by the fallback solver" if s["fallback_steps"] else ""
    print(f"  statuses: {s['status_counts']}{fallback}; step time median "
          f"{s['step_time_median_s'] * 1e6:.0f} us")
    for warning in s["warnings"]:
        print(f"  warning: {warning}")
    if s["failure"] is not None and status != "interrupted":
        print(f"  failed on: {s['failure']['criterion']}")
    print(f"  outputs: {out}/")


def _cmd_animate(args: argparse.Namespace) -> int:
    from .experiments.animate import animate_run

    path = animate_run(args.run_dir, args.out)
    print(f"animation: {path} (open it in a web browser; it needs no server or network)")
    return EXIT_OK


def _physics_line(name: str, r: dict[str, Any] | None) -> str:
    """Return the console line of one simulation of the physics check (its peaks)."""
    if r is None:
        return f"  {name:<12} none (the run recorded fewer than two samples)"
    ratio = r["torque_ratio_max"]
    torque = ("no torque limits" if ratio is None or ratio != ratio  # None or NaN
              else f"torque/limit {ratio:.3g}")
    return (f"  {name:<12} object off D(t) {r['deviation_pos_max_m'] * 1e3:.3g} mm, "
            f"internal force {r['internal_force_max_N']:.3g} N, follower support "
            f"{r['follower_support_min_N']:.3g}..{r['follower_support_max_N']:.3g} N, "
            f"slip {r['slip_max_m'] * 1e3:.3g} mm, {torque} ({r['wall_time_s']:.1f} s)"
            + ("" if not r.get("cause") else
               f"; first past a threshold: {r['cause']['kind']} at {r['cause']['t_s']:.3g} s"))


def _samples(text: str) -> int:
    """Return ``--delay``'s number of samples (>= 0)."""
    try:
        value = int(text)
    except ValueError:
        value = -1
    if value < 0:
        raise argparse.ArgumentTypeError(f"a whole number of samples >= 0, not {text!r}")
    return value


def _cmd_physics(args: argparse.Namespace) -> int:
    from .physics.command import check_run
    from .physics.plant import DivergedError

    try:
        p = check_run(args.run_dir, delay=args.delay)
    except DivergedError as err:  # the simulation blew up: a failed check, not bad input
        _err(str(err))
        return EXIT_FAILED
    for name in ("replay", "closed_loop"):
        print(_physics_line(name, p[name]))
    cause = ("" if p["cause"] is None else f" (cause: {p['cause']}, from t = "
             f"{p['cause_t_s']:.3f} s, sample {p['cause_sample']})")
    print(f"physics.status: {p['status']}{cause}" + "".join(f"\n  {w}" for w in p["reasons"]))
    if p["status"] == "ok" and p["oscillation"] is not None:  # below every threshold
        print(f"  note: {p['oscillation']['message']}")
    print(f"  outputs: {args.run_dir}/ (physics.png, report.html, summary.json)")
    if p["status"] != "ok":
        _err(f"physics check {p['status'].upper()}: {p['message']}")
        return EXIT_FAILED
    return EXIT_OK


def _cmd_reproduce(args: argparse.Namespace) -> int:
    from .experiments.outputs import check_unused_folder
    from .experiments.reproduce import is_reproduction_folder, reproduce

    if not is_reproduction_folder(args.out):  # its own earlier output is replaced freely
        check_unused_folder(Path(args.out), force=args.force, what="a reproduction")
    rep = reproduce(_output_folder(args.out), config_dir=args.configs,
                    progress=None if not args.quiet else False)
    print(f"Reproduction of Suh & Shin (1988), Sec. 4 -> {args.out}/")
    for label, run in rep.runs.items():
        s = run.summary
        mark = "" if run.ok else f"  [{s['status'].upper()}]"
        c = rep.checks.get(label)
        if c is None:
            print(f"  case ({label}) {s['experiment']:<28} {s['samples']} samples{mark}")
            continue
        print(f"  case ({label}) {s['experiment']:<28} q3 in [{c['q3_min_deg']:7.2f}, "
              f"{c['q3_max_deg']:7.2f}] deg, samples outside range: "
              f"{c['q3_samples_outside']:4d}, grasp {s['grasp_start_m'] * 1e3:.1f} -> "
              f"{s['grasp_end_m'] * 1e3:.1f} mm" + mark)
        for warning in s.get("warnings", []):
            print(f"      warning: {warning}")
    if rep.interrupted is not None:
        _err(f"interrupted in case ({rep.interrupted}); the cases done are written, "
             "without the figures; see reproduce.json")
        return EXIT_INTERRUPTED
    for claim, held in rep.checks["claims"].items():
        print(f"  {'yes' if held else 'NO '}  {claim.replace('_', ' ')}")
    print("  figures: fig5_joint3.png, fig6_grasp.png; details in reproduce.json")
    return EXIT_OK if rep.ok else EXIT_FAILED


def _cmd_collisions(args: argparse.Namespace) -> int:
    from .experiments.avoidance import (
        CLAIM_WORDS,
        compare_avoidance,
        describe,
        is_comparison_folder,
        variant_experiments,
    )
    from .experiments.config import safe_name
    from .experiments.outputs import check_unused_folder

    exps = variant_experiments(args.config)  # bad input: exit 2 before any folder is made
    out = Path(args.out if args.out else Path("runs") / safe_name(exps["avoiding"].name)
               / "collisions")
    if not is_comparison_folder(out):  # its own earlier output is replaced freely
        check_unused_folder(out, force=args.force, what="a comparison")
    comparison = compare_avoidance(args.config, _output_folder(out),
                                   progress=None if not args.quiet else False,
                                   plots=not args.no_plots, animate=args.animate,
                                   expect_penetration=args.expect_penetration)
    print(f"{exps['avoiding'].name}: collision avoidance on and off, and the fixed grasp "
          f"-> {out}/")
    for line in describe(comparison):
        print(line)
    if comparison.interrupted is not None:
        _err(f"interrupted in the run '{comparison.interrupted}'; the runs done are written, "
             "without the figure; see collisions.json")
        return EXIT_INTERRUPTED
    print("  figure: collisions.png; details in collisions.json")
    if not comparison.ok:  # a claim failed (the runs without avoidance are measured only)
        failed = [CLAIM_WORDS[k] for k, held in comparison.checks["claims"].items() if not held]
        _err(f"claim not met: {'; '.join(failed)}")
        return EXIT_FAILED
    return EXIT_OK


def _cmd_solvers(args: argparse.Namespace) -> int:
    from .solvers import list_solvers

    table = [("SOLVER", "INSTALLED", "BOUNDS", "METHOD")]
    missing = []
    for r in list_solvers():
        table.append((r.name, "yes" if r.available else "no",
                      "hard" if r.hard_bounds else "not enforced", r.description))
        if not r.available:
            missing.append(f"  {r.name:<14} pip install 'dualarm-qp[{r.extra}]'" if r.extra
                           else f"  {r.name:<14} not available")
    widths = [max(len(row[i]) for row in table) for i in range(3)]
    for row in table:
        print("  ".join(cell.ljust(w) for cell, w in zip(row[:3], widths, strict=True))
              + "  " + row[3])
    if missing:
        print("\nTo install a missing backend:")
        print("\n".join(missing))
    return EXIT_OK


def _cmd_bench(args: argparse.Namespace) -> int:
    from .bench.report import format_table, jobs_line, table_legend, write_report
    from .bench.runner import BenchInterrupted, BenchSettings, run_bench
    from .experiments.reproduce import BENCH_CONFIGS, bundled_config
    from .solvers import available_solvers

    configs = args.configs or [bundled_config(name) for name in BENCH_CONFIGS]
    if args.solvers is None:
        solvers = available_solvers()
    else:
        solvers = [s.strip() for s in args.solvers.split(",") if s.strip()]
        if not solvers:
            raise InvalidInputError(f"--solvers names no solver ({args.solvers!r}); give "
                                    "comma-separated names, or leave the option out for "
                                    "all available: " + ", ".join(available_solvers()))
    from .experiments.options import check_solver_options, parse_solver_options

    solver_options = parse_solver_options(args.solver_option)
    check_solver_options(solver_options, used=solvers)
    settings = BenchSettings(repeat=args.repeat, duration=args.duration,
                             solver_options=solver_options)
    out = _output_folder(args.out)
    try:
        result = run_bench(configs, solvers, out, settings=settings,
                           log=None if args.quiet else lambda line: print(line, file=sys.stderr))
    except BenchInterrupted as stop:
        result = stop.result
    meta = {"machine": result.machine, "settings": settings.as_dict(),
            "configs": [str(c) for c in configs], "solvers": solvers,
            "jobs_computed_this_run": result.computed, "jobs_planned": result.planned,
            "interrupted": result.interrupted}
    with SignalHold():  # a signal during the report: finish it, then exit 130
        rows = write_report(out, result.records, meta, plots=not args.no_plots)
        print(format_table(rows))
        print(table_legend())
        print(f"outputs: {out}/bench.json, bench.csv"
              + ("" if args.no_plots else ", bench.png")
              + f" ({jobs_line(result.computed, len(rows), result.planned)})")
        sys.stdout.flush()
    if result.interrupted is not None:
        _err(f"interrupted ({result.interrupted}): {len(result.records)} of "
             f"{result.planned} jobs done and stored, the job under way was not stored; "
             "run the same command again to resume")
        return EXIT_INTERRUPTED
    failures = result.failures
    if failures:
        _err(f"{len(failures)} of {len(result.records)} jobs failed"
             + (" (all of them)" if len(failures) == len(result.records) else "")
             + "; the reasons are listed under the table and in bench.csv's 'error' column")
        return EXIT_FAILED
    return EXIT_OK


def _cmd_sweep(args: argparse.Namespace) -> int:
    from .sweep.cluster import quiet_dask_logs
    from .sweep.runner import SchedulerLost, SweepSettings, check_sweep_folder, run_sweep
    from .sweep.spec import load_sweep

    spec = load_sweep(args.sweep)
    settings = SweepSettings(workers=args.workers, scheduler=args.scheduler, batch=args.batch,
                             progress=not args.quiet)
    fresh = not Path(args.out).exists()
    out = _output_folder(check_sweep_folder(Path(args.out)))
    try:
        with quiet_dask_logs(restore=False):  # Dask's own lines: the process ends after
            result = run_sweep(spec, out, settings=settings, log=None if args.quiet
                               else lambda line: print(line, file=sys.stderr))
    except SchedulerLost as err:
        _err(f"{err} (the table holds the points done)")
        return EXIT_FAILED
    except DualArmError:  # bad input found before anything ran: leave no empty folder
        if fresh and out.is_dir() and not any(out.iterdir()):
            out.rmdir()
        raise
    done = result.finished
    print(f"sweep {spec.name}: {result.planned} points, {done} done "
          f"({result.computed} computed now), {len(result.failures)} failed -> "
          f"{out}/results.parquet, results.csv")
    if result.interrupted is not None:
        _err(f"interrupted ({result.interrupted}): {done} of {result.planned} points stored; "
             "run the same command again to resume")
        return EXIT_INTERRUPTED
    return _sweep_report(out, unrun=len(result.unrun),
                         why="; ".join(sorted(set(result.unrun.values()))))


def _sweep_report(out: Path, *, unrun: int = 0, why: str = "") -> int:
    from .sweep.report import write_report

    with SignalHold():  # a signal during the report: finish it, then exit 130
        path = write_report(out)
        print(f"report: {path}")
        sys.stdout.flush()
    if unrun:
        _err(f"{unrun} points could not be run ({why or 'their workers died repeatedly'}); "
             "they are listed as interrupted; run the same command again to resume")
        return EXIT_FAILED
    return EXIT_OK


def _cmd_sweep_report(args: argparse.Namespace) -> int:
    return _sweep_report(Path(args.dir))


def build_parser() -> argparse.ArgumentParser:
    """Build the argument parser (exposed for documentation and tests)."""
    p = argparse.ArgumentParser(
        prog="dualarm-qp",
        description="Coordinate two arms carrying one object with a sliding follower grasp "
                    "(Suh & Shin 1988): run experiments, reproduce the paper, compare solvers.",
    )
    p.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    p.add_argument("--debug", action="store_true", help="show tracebacks of internal errors")
    sub = p.add_subparsers(dest="command", metavar="COMMAND")

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
    r.set_defaults(func=_cmd_run)

    a = sub.add_parser("animate", help="write the 3D animation (animation.html) of a "
                                       "finished run")
    a.add_argument("run_dir", type=Path, metavar="RUN_DIR",
                   help="output folder of 'dualarm-qp run' (or a case folder of a "
                        "reproduction)")
    a.add_argument("--out", type=Path, default=None,
                   help="file to write (default RUN_DIR/animation.html, then listed in the "
                        "run's summary.json)")
    a.set_defaults(func=_cmd_animate)

    ph = sub.add_parser("physics", help="check a finished run in MuJoCo: rigid replay and "
                                        "closed loop, with a verdict (docs/physics.md)")
    ph.add_argument("run_dir", type=Path, metavar="RUN_DIR",
                    help="output folder of 'dualarm-qp run'")
    ph.add_argument("--delay", nargs="?", const=1, default=None, type=_samples,
                    metavar="N", help="closed loop N samples late (1 when N is left out; "
                    "overrides the file's physics.delay)")
    ph.set_defaults(func=_cmd_physics)

    rp = sub.add_parser("reproduce", help="run the paper's three PUMA beam cases and the "
                        "same task with hard limits, draw Figs. 5-6")
    rp.add_argument("--out", default="reproduction", help="output folder (default reproduction)")
    rp.add_argument("--configs", type=Path, default=None,
                    help="folder with the three YAML files (default: the bundled copies)")
    rp.add_argument("--quiet", action="store_true", help="no progress bar")
    rp.add_argument("--force", action="store_true",
                    help="write into a folder that holds other files, keeping them (an "
                         "earlier reproduction there is replaced even without --force)")
    rp.set_defaults(func=_cmd_reproduce)

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
    c.set_defaults(func=_cmd_collisions)

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
    b.set_defaults(func=_cmd_bench)

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
    w.set_defaults(func=_cmd_sweep)

    wr = sub.add_parser("sweep-report", help="draw the maps of a sweep folder into "
                        "report.html (also done at the end of 'sweep')")
    wr.add_argument("dir", metavar="DIR", help="the sweep's --out folder")
    wr.set_defaults(func=_cmd_sweep_report)

    s = sub.add_parser("solvers", help="list the solvers and whether they are installed")
    s.set_defaults(func=_cmd_solvers)
    for command in sub.choices.values():  # --debug after the command too
        command.add_argument("--debug", action="store_true", default=argparse.SUPPRESS,
                             help="show tracebacks of internal errors")
    return p


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

    An error that an interrupt caused (an import cut short) is reported as the interrupt.
    """
    try:
        code = int(args.func(args))
        sys.stdout.flush()  # a closed pipe shows here, not in the flush at exit
    except BrokenPipeError:  # e.g. `dualarm-qp solvers | head -1`: end quietly
        _drop_stdout()
        return EXIT_BROKEN_PIPE
    except KeyboardInterrupt as stop:
        _err(f"interrupted ({stop})" if str(stop) else "interrupted")
        return EXIT_INTERRUPTED
    except DualArmError as err:
        if interrupt_requested() is None:
            _err(str(err))
            return EXIT_BAD_INPUT
        code = EXIT_FAILED  # came from the interrupt: reported below
    except Exception as err:
        if args.debug:
            traceback.print_exc()
        if interrupt_requested() is None:  # an internal error: say so plainly, no traceback
            _err(f"internal error: {type(err).__name__}: {err} "
                 "(rerun with --debug for details)")
            return EXIT_FAILED
        code = EXIT_FAILED  # caused by the interrupt (an import cut short): reported below
    stopped = interrupt_requested()
    if stopped is not None and code != EXIT_INTERRUPTED:
        _err(f"interrupted ({stopped})")
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


if __name__ == "__main__":
    sys.exit(main())
