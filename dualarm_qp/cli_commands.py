"""The commands of ``dualarm-qp``: what each does, and the exit code it returns.

:mod:`dualarm_qp.cli` parses the arguments and calls one of the ``cmd_*`` functions
here; each returns an exit code (:data:`EXIT_OK`, ...; see :mod:`dualarm_qp.cli`) and
prints what the user reads (:func:`print_run_summary` for a run).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ._signals import SignalHold
from .errors import DualArmError, InvalidInputError

if TYPE_CHECKING:
    from .experiments.figures.process import FigureProcess

EXIT_OK, EXIT_FAILED, EXIT_BAD_INPUT = 0, 1, 2
EXIT_INTERRUPTED, EXIT_BROKEN_PIPE = 130, 141  # 128 + SIGINT, 128 + SIGPIPE


def print_error(msg: str) -> None:
    """Print one error line for the user (standard error)."""
    print(f"dualarm-qp: error: {msg}", file=sys.stderr)


def output_folder(path: str | Path) -> Path:
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


def cmd_run(args: argparse.Namespace) -> int:
    """``dualarm-qp run``: one experiment from a YAML file.

    The figures' process starts first, before anything heavy is imported: it imports
    matplotlib while this one imports the rest and runs
    (:mod:`~dualarm_qp.experiments.figures.process`).
    """
    from .experiments.figures.process import FigureProcess

    figures = None if args.no_plots else FigureProcess.start()
    try:
        return _run(args, figures)
    finally:
        if figures is not None:
            figures.close()


def _run(args: argparse.Namespace, figures: FigureProcess | None) -> int:
    """Run one experiment file (``dualarm-qp run``); its figures drawn by ``figures``."""
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
        from .physics.compliant import compliant_experiment
        from .physics.plant import DivergedError, MujocoPlant

        blown_up = (DivergedError,)
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
    out = output_folder(out)
    try:
        outcome = run_experiment(exp, out, progress=None if not args.quiet else False,
                                 plots=not args.no_plots, animate=args.animate,
                                 controller=controller, plant=plant, figures=figures)
    except blown_up as err:  # the simulation blew up: a failed run, not bad input
        if new_folder and not any(out.iterdir()):
            out.rmdir()  # nothing was written: leave no empty folder
        print_error(str(err))
        return EXIT_FAILED
    print_run_summary(outcome.summary, str(out))
    if outcome.interrupted:
        print_error(f"{outcome.summary['message']}; the samples done are written")
        return EXIT_INTERRUPTED
    if not outcome.ok:
        print_error(outcome.summary["message"])
        return EXIT_FAILED
    return EXIT_OK


def clearance_line(r: dict[str, Any]) -> str:
    """Return the console line of ``realised_limits.clearance`` (the smallest distance)."""
    d = r["min_m"]
    smallest = ("no pair" if d is None
                else f"{d * 1e3:.1f} mm ({r['pair']}, sample {r['sample']})")
    rule = (f"safety distance {r['safety_distance_m'] * 1e3:.3g} mm "
            f"{'kept' if r['kept'] else 'NOT KEPT'} (allowance {r['allowance_m'] * 1e3:.3g} mm)"
            if r["enforced"] else "measured only (collision avoidance off)")
    return (f"    {'clearance':<12} smallest {smallest}; {rule}"
            + ("; PENETRATION" if r["penetration"] else ""))


def torque_line(r: dict[str, Any]) -> str:
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
            print(clearance_line(r))
            continue
        if part == "torque":  # joint torques, not positions
            print(torque_line(r))
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


def cmd_animate(args: argparse.Namespace) -> int:
    """``dualarm-qp animate``: the 3D animation of a finished run."""
    from .experiments.animate import animate_run

    path = animate_run(args.run_dir, args.out)
    print(f"animation: {path} (open it in a web browser; it needs no server or network)")
    return EXIT_OK


def physics_line(name: str, r: dict[str, Any] | None) -> str:
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


def cmd_physics(args: argparse.Namespace) -> int:
    """``dualarm-qp physics``: a finished run checked in MuJoCo, with a verdict."""
    from .physics.command import check_run
    from .physics.plant import DivergedError

    try:
        p = check_run(args.run_dir, delay=args.delay)
    except DivergedError as err:  # the simulation blew up: a failed check, not bad input
        print_error(str(err))
        return EXIT_FAILED
    for name in ("replay", "closed_loop"):
        print(physics_line(name, p[name]))
    cause = ("" if p["cause"] is None else f" (cause: {p['cause']}, from t = "
             f"{p['cause_t_s']:.3f} s, sample {p['cause_sample']})")
    print(f"physics.status: {p['status']}{cause}" + "".join(f"\n  {w}" for w in p["reasons"]))
    if p["status"] == "ok" and p["oscillation"] is not None:  # below every threshold
        print(f"  note: {p['oscillation']['message']}")
    print(f"  outputs: {args.run_dir}/ (physics.png, report.html, summary.json)")
    if p["status"] != "ok":
        print_error(f"physics check {p['status'].upper()}: {p['message']}")
        return EXIT_FAILED
    return EXIT_OK


def cmd_reproduce(args: argparse.Namespace) -> int:
    """``dualarm-qp reproduce``: the paper's cases and Figs. 5-6."""
    from .experiments.outputs import check_unused_folder
    from .experiments.reproduce import is_reproduction_folder, reproduce

    if not is_reproduction_folder(args.out):  # its own earlier output is replaced freely
        check_unused_folder(Path(args.out), force=args.force, what="a reproduction")
    rep = reproduce(output_folder(args.out), config_dir=args.configs,
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
        print_error(f"interrupted in case ({rep.interrupted}); the cases done are written, "
                    "without the figures; see report.html and reproduce.json")
        return EXIT_INTERRUPTED
    for claim, held in rep.checks["claims"].items():
        print(f"  {'yes' if held else 'NO '}  {claim.replace('_', ' ')}")
    print(f"  open {args.out}/report.html: each case, the claims and the figures "
          "(fig5_joint3.png, fig6_grasp.png); every number in reproduce.json")
    return EXIT_OK if rep.ok else EXIT_FAILED


def cmd_collisions(args: argparse.Namespace) -> int:
    """``dualarm-qp collisions``: a file with and without collision avoidance."""
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
    comparison = compare_avoidance(args.config, output_folder(out),
                                   progress=None if not args.quiet else False,
                                   plots=not args.no_plots, animate=args.animate,
                                   expect_penetration=args.expect_penetration)
    print(f"{exps['avoiding'].name}: collision avoidance on and off, and the fixed grasp "
          f"-> {out}/")
    for line in describe(comparison):
        print(line)
    if comparison.interrupted is not None:
        print_error(f"interrupted in the run '{comparison.interrupted}'; the runs done are "
                    "written, without the figure; see collisions.json")
        return EXIT_INTERRUPTED
    print("  figure: collisions.png; details in collisions.json")
    if not comparison.ok:  # a claim failed (the runs without avoidance are measured only)
        failed = [CLAIM_WORDS[k] for k, held in comparison.checks["claims"].items() if not held]
        print_error(f"claim not met: {'; '.join(failed)}")
        return EXIT_FAILED
    return EXIT_OK


def cmd_solvers(args: argparse.Namespace) -> int:
    """``dualarm-qp solvers``: every solver and whether it is installed."""
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


def cmd_bench(args: argparse.Namespace) -> int:
    """``dualarm-qp bench``: every config with every solver, compared."""
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
    out = output_folder(args.out)
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
        print_error(f"interrupted ({result.interrupted}): {len(result.records)} of "
                    f"{result.planned} jobs done and stored, the job under way was not stored; "
                    "run the same command again to resume")
        return EXIT_INTERRUPTED
    failures = result.failures
    if failures:
        print_error(f"{len(failures)} of {len(result.records)} jobs failed"
                    + (" (all of them)" if len(failures) == len(result.records) else "")
                    + "; the reasons are listed under the table and in bench.csv's 'error' column")
        return EXIT_FAILED
    return EXIT_OK


def cmd_sweep(args: argparse.Namespace) -> int:
    """``dualarm-qp sweep``: an experiment over a grid or sample of its settings."""
    from .sweep.cluster import quiet_dask_logs
    from .sweep.runner import SchedulerLost, SweepSettings, check_sweep_folder, run_sweep
    from .sweep.spec import load_sweep

    spec = load_sweep(args.sweep)
    settings = SweepSettings(workers=args.workers, scheduler=args.scheduler, batch=args.batch,
                             progress=not args.quiet)
    fresh = not Path(args.out).exists()
    out = output_folder(check_sweep_folder(Path(args.out)))
    try:
        with quiet_dask_logs(restore=False):  # Dask's own lines: the process ends after
            result = run_sweep(spec, out, settings=settings, log=None if args.quiet
                               else lambda line: print(line, file=sys.stderr))
    except SchedulerLost as err:
        print_error(f"{err} (the table holds the points done)")
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
        print_error(f"interrupted ({result.interrupted}): {done} of {result.planned} points "
                    "stored; run the same command again to resume")
        return EXIT_INTERRUPTED
    return sweep_report_of(out, unrun=len(result.unrun),
                         why="; ".join(sorted(set(result.unrun.values()))))


def sweep_report_of(out: Path, *, unrun: int = 0, why: str = "") -> int:
    """Draw the maps of the sweep folder ``out`` into its report."""
    from .sweep.report import write_report

    with SignalHold():  # a signal during the report: finish it, then exit 130
        path = write_report(out)
        print(f"report: {path}")
        sys.stdout.flush()
    if unrun:
        print_error(f"{unrun} points could not be run ({why or 'their workers died repeatedly'}); "
                    "they are listed as interrupted; run the same command again to resume")
        return EXIT_FAILED
    return EXIT_OK


def cmd_sweep_report(args: argparse.Namespace) -> int:
    """``dualarm-qp sweep-report``: the maps of a sweep folder."""
    return sweep_report_of(Path(args.dir))


__all__ = ["EXIT_BAD_INPUT", "EXIT_BROKEN_PIPE", "EXIT_FAILED", "EXIT_INTERRUPTED", "EXIT_OK",
           "cmd_animate", "cmd_bench", "cmd_collisions", "cmd_physics", "cmd_reproduce",
           "cmd_run", "cmd_solvers", "cmd_sweep", "cmd_sweep_report", "output_folder",
           "print_error", "print_run_summary"]
