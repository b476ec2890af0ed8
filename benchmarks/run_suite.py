"""Run every solver on every instance of the step suite and score them (qpbenchmark-style).

    python benchmarks/run_suite.py                          # full suite, every solver
    python benchmarks/run_suite.py --every 50 --solvers nullspace,qp:daqp
    python benchmarks/run_suite.py --out bench_out/suite    # also write suite.json/.csv

An instance is solved only when the solver's status says so AND its residuals (and
objective) are within the tolerance profile; see dualarm_qp/bench/suite.py.
"""

from __future__ import annotations

import argparse
import csv
import json
import sys
from pathlib import Path

import numpy as np

from dualarm_qp._io import jsonable
from dualarm_qp.bench.runner import machine_info
from dualarm_qp.bench.suite import (
    PROFILES,
    format_suite_table,
    load_suite,
    run_solver,
    score,
)
from dualarm_qp.solvers import available_solvers

DEFAULT_SUITE = Path(__file__).resolve().parent / "data" / "step_suite.npz"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--suite", type=Path, default=DEFAULT_SUITE)
    ap.add_argument("--solvers", help="comma-separated (default: every available solver)")
    ap.add_argument("--profiles", default="default,high_accuracy,low_accuracy")
    ap.add_argument("--every", type=int, default=1, help="use every k-th instance")
    ap.add_argument("--out", type=Path, default=None)
    ap.add_argument("--markdown", action="store_true")
    args = ap.parse_args(argv)
    suite = load_suite(args.suite)
    if args.every > 1:
        suite = suite.subset(np.arange(0, len(suite), args.every))
    solvers = args.solvers.split(",") if args.solvers else available_solvers()
    machine = machine_info()
    print(f"{len(suite)} instances ({int((~suite.feasible).sum())} infeasible), "
          f"{len(solvers)} solvers; {machine['cpu']}, {machine['cpus']} cpus, "
          f"load {machine['load_average']}", file=sys.stderr)
    runs = [run_solver(suite, s) for s in solvers]
    all_rows = []
    for name in args.profiles.split(","):
        rows = score(suite, runs, PROFILES[name])
        all_rows += rows
        print(f"\nprofile {name}: eq {PROFILES[name].equality:g}, bounds "
              f"{PROFILES[name].bounds:g}, objective {PROFILES[name].objective:g} (relative)")
        print(format_suite_table(rows, markdown=args.markdown))
    if args.out is not None:
        args.out.mkdir(parents=True, exist_ok=True)
        (args.out / "suite.json").write_text(json.dumps(jsonable(
            {"machine": machine, "instances": len(suite), "rows": all_rows}), indent=2) + "\n")
        with open(args.out / "suite.csv", "w", newline="", encoding="utf-8") as fh:
            w = csv.DictWriter(fh, fieldnames=list(all_rows[0]))
            w.writeheader()
            w.writerows(jsonable(all_rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
