"""Command-line interface: ``dualarm-qp run | reproduce | bench | solvers``.

Exit codes: 0 success, 1 the run failed (what it completed is still written), 2 bad
input (configuration, arguments, missing solver).
"""

from __future__ import annotations

import argparse
import sys
import traceback
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from . import __version__
from .errors import DualArmError, InvalidInputError

EXIT_OK, EXIT_FAILED, EXIT_BAD_INPUT = 0, 1, 2


def _err(msg: str) -> None:
    print(f"dualarm-qp: error: {msg}", file=sys.stderr)


def _output_folder(path: str | Path) -> Path:
    """Create the output folder, or say plainly why it cannot be (bad input, exit 2)."""
    out = Path(path)
    try:
        out.mkdir(parents=True, exist_ok=True)
        probe = out / ".write-test"
        probe.touch()
        probe.unlink()
    except OSError as err:
        reason = err.strerror or str(err)
        if isinstance(err, (FileExistsError, NotADirectoryError)):
            reason = "a file is in the way"
        raise InvalidInputError(f"cannot write the output folder {out}: {reason}") from None
    return out


def _cmd_run(args: argparse.Namespace) -> int:
    from .experiments.config import load_config
    from .experiments.run import run_experiment
    from .experiments.setup import build_experiment

    exp = build_experiment(load_config(args.config), str(args.config), solver=args.solver)
    exp.controller()  # fail early (exit 2) on an unknown or missing solver
    out = _output_folder(args.out if args.out else Path("runs") / exp.name
                         / exp.solver_name.replace(":", "_"))
    outcome = run_experiment(exp, out, progress=None if not args.quiet else False,
                             plots=not args.no_plots)
    print_run_summary(outcome.summary, str(out))
    if not outcome.ok:
        _err(outcome.summary["message"])
        return EXIT_FAILED
    return EXIT_OK


def print_run_summary(s: dict[str, Any], out: str) -> None:
    """Print the console summary of one run (from its summary.json content)."""
    print(f"{s['experiment']}: solver {s['solver']}, {s['samples']} samples, "
          f"{'completed' if s['completed'] else 'FAILED'}")
    print(f"  path completed: {s['path_completed_pct']:.1f}%; time lost to scaling: "
          f"{s['time_lost_to_scaling_s']:.3g} s")
    print(f"  leader tracking error max: {s['leader_pos_err_max_m']:.3g} m, "
          f"{s['leader_rot_err_max_rad']:.3g} rad; closure error max: "
          f"{s['closure_pos_err_max_m']:.3g} m, {s['closure_rot_err_max_rad']:.3g} rad")
    limits = "hard limits" if s["hard_limits"] else "limits not enforced by this solver"
    print(f"  realised motion, worst share of each limit ({limits}; above 1 is outside):")
    for part, r in s["realised_limits"].items():
        print(f"    {part:<9} range {r['range_ratio_max']:.3g} ({r['worst_range']}), "
              f"speed {r['speed_ratio_max']:.3g} ({r['worst_speed'] or '-'})")
    print(f"  grasp: {s['grasp_start_m'] * 1e3:.1f} -> {s['grasp_end_m'] * 1e3:.1f} mm; "
          f"smallest singular value: leader {s['sigma_min']['leader']:.3g}, "
          f"follower {s['sigma_min']['follower']:.3g}")
    fallback = f", {s['fallback_steps']} by the fallback solver" if s["fallback_steps"] else ""
    print(f"  statuses: {s['status_counts']}{fallback}; step time median "
          f"{s['step_time_median_s'] * 1e6:.0f} us")
    for warning in s["warnings"]:
        print(f"  warning: {warning}")
    if s["failure"] is not None:
        print(f"  failed on: {s['failure']['criterion']}")
    print(f"  outputs: {out}/")


def _cmd_reproduce(args: argparse.Namespace) -> int:
    from .experiments.reproduce import reproduce

    rep = reproduce(_output_folder(args.out), config_dir=args.configs,
                    progress=None if not args.quiet else False)
    print(f"Reproduction of Suh & Shin (1988), Sec. 4 -> {args.out}/")
    for label, run in rep.runs.items():
        c = rep.checks[label]
        s = run.summary
        print(f"  case ({label}) {s['experiment']:<28} q3 in [{c['q3_min_deg']:7.2f}, "
              f"{c['q3_max_deg']:7.2f}] deg, samples outside range: "
              f"{c['q3_samples_outside']:4d}, grasp {s['grasp_start_m'] * 1e3:.1f} -> "
              f"{s['grasp_end_m'] * 1e3:.1f} mm"
              + ("" if run.ok else "  [FAILED]"))
    for claim, held in rep.checks["claims"].items():
        print(f"  {'yes' if held else 'NO '}  {claim.replace('_', ' ')}")
    print("  figures: fig5_joint3.png, fig6_grasp.png; details in reproduce.json")
    return EXIT_OK if rep.ok else EXIT_FAILED


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
    from .bench.report import format_table, write_report
    from .bench.runner import BenchSettings, run_bench
    from .experiments.reproduce import BENCH_CONFIGS, bundled_config
    from .solvers import available_solvers

    configs = args.configs or [bundled_config(name) for name in BENCH_CONFIGS]
    solvers = [s.strip() for s in args.solvers.split(",") if s.strip()] if args.solvers \
        else available_solvers()
    settings = BenchSettings(repeat=args.repeat, duration=args.duration)
    out = _output_folder(args.out)
    result = run_bench(configs, solvers, out, settings=settings,
                       log=None if args.quiet else lambda line: print(line, file=sys.stderr))
    meta = {"machine": result.machine, "settings": settings.as_dict(),
            "configs": [str(c) for c in configs], "solvers": solvers,
            "jobs_computed_this_run": result.computed}
    rows = write_report(out, result.records, meta, plots=not args.no_plots)
    print(format_table(rows))
    print(f"outputs: {out}/bench.json, bench.csv" + ("" if args.no_plots else ", bench.png")
          + f" ({result.computed} of {len(rows)} jobs computed, the rest resumed)")
    if not result.ok:
        _err("some jobs failed; see the 'error' column")
        return EXIT_FAILED
    return EXIT_OK


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
    r.add_argument("--out", help="output folder (default runs/<name>/<solver>)")
    r.add_argument("--no-plots", action="store_true", help="skip the PNG plots")
    r.add_argument("--quiet", action="store_true", help="no progress bar")
    r.set_defaults(func=_cmd_run)

    rp = sub.add_parser("reproduce", help="run the paper's three PUMA beam cases, draw Figs. 5-6")
    rp.add_argument("--out", default="reproduction", help="output folder (default reproduction)")
    rp.add_argument("--configs", type=Path, default=None,
                    help="folder with the three YAML files (default: the bundled copies)")
    rp.add_argument("--quiet", action="store_true", help="no progress bar")
    rp.set_defaults(func=_cmd_reproduce)

    b = sub.add_parser("bench", help="run every config with every solver, compare them")
    b.add_argument("configs", nargs="*", type=Path, metavar="CONFIG",
                   help="experiment YAML files (default: the beam with speed limits and "
                        "the curved bar)")
    b.add_argument("--solvers", help="comma-separated solver names (default: all available)")
    b.add_argument("--out", default="bench_out", help="output folder (default bench_out); "
                   "finished jobs stored there are reused, so a bench resumes")
    b.add_argument("--repeat", type=int, default=1,
                   help="rollouts per job; their step timings are pooled (default 1)")
    b.add_argument("--duration", type=float, default=None,
                   help="override every config's run length [s] (e.g. for a quick check)")
    b.add_argument("--no-plots", action="store_true", help="skip bench.png")
    b.add_argument("--quiet", action="store_true", help="no per-job progress lines")
    b.set_defaults(func=_cmd_bench)

    s = sub.add_parser("solvers", help="list the solvers and whether they are installed")
    s.set_defaults(func=_cmd_solvers)
    return p


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``dualarm-qp`` command."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if getattr(args, "func", None) is None:
        parser.print_help()
        return EXIT_BAD_INPUT
    try:
        return int(args.func(args))
    except DualArmError as err:
        _err(str(err))
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        _err("interrupted")
        return 130
    except Exception as err:  # an internal error: say so plainly, no traceback by default
        if args.debug:
            traceback.print_exc()
        _err(f"internal error: {type(err).__name__}: {err} (rerun with --debug for details)")
        return EXIT_FAILED


if __name__ == "__main__":
    sys.exit(main())
