"""Record the exact solver's answers and their certificates (tests/solvers/data/exact_answers.npz).

The file pins the answers of the ``nullspace`` solver (x, status, conflicting rows,
null-space dimension) and the verdict of :func:`~dualarm_qp.solvers.certify.certify`
on them, for

* every instance of ``benchmarks/data/step_suite.npz`` (the PUMA beam, boxes only), and
* the steps the solver is handed in rollouts of a few shipped configurations (limits,
  both grasps sliding, a pair of Pandas, collision rows, a wrist singularity), every
  ``--every``-th step kept.

The committed file was written by the Python implementation of the solver and the
certificate, before they moved to the compiled kernel (``src/kernel``). Whoever changes
the implementation (not the algorithm) must reproduce these answers:
``tests/solvers/test_recorded_answers.py`` reads the file back and compares.

    python benchmarks/record_exact.py            # writes the committed file
    python benchmarks/record_exact.py --out /tmp/answers.npz --every 5
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

import numpy as np

from dualarm_qp.bench.suite import load_suite
from dualarm_qp.experiments.config import load_config
from dualarm_qp.experiments.run import run_experiment
from dualarm_qp.experiments.setup import build_experiment
from dualarm_qp.solvers.certify import certify
from dualarm_qp.solvers.nullspace import NullspaceSolver
from dualarm_qp.step.problem import StepProblem

ROOT = Path(__file__).resolve().parent.parent
DEFAULT_OUT = ROOT / "tests" / "solvers" / "data" / "exact_answers.npz"
SUITE = ROOT / "benchmarks" / "data" / "step_suite.npz"
CONFIGS = ("puma_beam_limits", "puma_beam_tight_limits", "puma_beam_wrist_singular",
           "both_sliding_bar", "panda_pair", "panda_pair_shelf", "ur5_pair_collision")
ARRAYS = ("A", "b", "weights", "center", "lower", "upper", "G", "h")
STRINGS = ("names", "row_names", "eq_names", "lower_by", "upper_by")


def rollout_problems(config: str, every: int) -> list[StepProblem]:
    """The problems the nullspace solver is handed in a rollout of ``config``."""
    seen: list[StepProblem] = []
    original = NullspaceSolver.solve

    def spy(self: NullspaceSolver, problem: StepProblem) -> Any:
        seen.append(problem)
        return original(self, problem)

    NullspaceSolver.solve = spy  # type: ignore[method-assign]
    try:
        path = ROOT / "configs" / f"{config}.yaml"
        exp = build_experiment(load_config(path), str(path), solver="nullspace")
        run_experiment(exp, None, progress=False, plots=False)
    finally:
        NullspaceSolver.solve = original  # type: ignore[method-assign]
    return seen[::every]


def pack(problems: list[StepProblem], source: list[str]) -> dict[str, np.ndarray]:
    """Problems, the solver's answers and the certificates as flat arrays."""
    solver = NullspaceSolver()
    out: dict[str, list[Any]] = {k: [] for k in ARRAYS}
    shapes: dict[str, list[tuple[int, ...]]] = {k: [] for k in ARRAYS}
    meta: list[dict[str, Any]] = []
    xs, nullity, status, verdict = [], [], [], []
    for p in problems:
        for k in ARRAYS:
            a = np.asarray(getattr(p, k), dtype=np.float64)
            out[k].append(a.ravel())
            shapes[k].append(a.shape)
        sol = solver.solve(p)
        cert = certify(p, sol, solver.tol)
        xs.append(sol.x)
        nullity.append(int(sol.extras.get("nullity", -1)))
        status.append(sol.status.value)
        verdict.append(cert.status.value)
        meta.append({"strings": {k: list(getattr(p, k)) for k in STRINGS},
                     "n_grasp": p.n_grasp,
                     "conflicts": list(sol.extras.get("conflicts", ()))})
    packed: dict[str, np.ndarray] = {}
    for k in ARRAYS:
        packed[k] = np.concatenate(out[k]) if out[k] else np.zeros(0)
        packed[k + "_shape"] = np.array([s + (0,) * (2 - len(s)) for s in shapes[k]])
        packed[k + "_ndim"] = np.array([len(s) for s in shapes[k]])
    packed["x"] = np.concatenate(xs)
    packed["nullity"] = np.array(nullity)
    packed["status"] = np.array(status)
    packed["verdict"] = np.array(verdict)
    packed["source"] = np.array(source)
    packed["meta"] = np.array(json.dumps(meta))
    return packed


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=DEFAULT_OUT)
    ap.add_argument("--every", type=int, default=4, help="keep every k-th rollout step")
    args = ap.parse_args()
    problems = list(load_suite(SUITE).problems)
    source = ["step_suite"] * len(problems)
    for config in CONFIGS:
        got = rollout_problems(config, args.every)
        print(f"{config}: {len(got)} steps kept")
        problems += got
        source += [config] * len(got)
    np.savez_compressed(args.out, **pack(problems, source))
    print(f"wrote {len(problems)} instances to {args.out}")


if __name__ == "__main__":
    main()
