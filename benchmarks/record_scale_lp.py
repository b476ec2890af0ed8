"""Record the task-scale LP's answers (tests/solvers/data/scale_lp_answers.npz).

The largest feasible task scale of a step (:mod:`dualarm_qp.solvers._scale`) ends in a
small LP, ``maximise s  s.t.  M t + a s <= g,  s_lo <= s <= s_hi``, solved by a revised
simplex with Bland's rule. This script pins its inputs and answers (feasible or not,
``t``, ``s``, the rows of the final basis or of the dual ray) for

* the LP of every instance of ``benchmarks/data/step_suite.npz``, and
* every LP asked in rollouts of a few shipped configurations (the steps the scale
  policy slows, collision rows, a pair of Pandas).

The committed file was written by the Python simplex, before it moved to the compiled
kernel (``src/kernel``); ``tests/solvers/test_scale_lp_recorded.py`` compares.

    python benchmarks/record_scale_lp.py
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import numpy as np

from dualarm_qp.bench.suite import load_suite
from dualarm_qp.experiments.config import load_config
from dualarm_qp.experiments.run import run_experiment
from dualarm_qp.experiments.setup import build_experiment
from dualarm_qp.solvers import _scale

ROOT = Path(__file__).resolve().parent.parent
DEFAULT_OUT = ROOT / "tests" / "solvers" / "data" / "scale_lp_answers.npz"
SUITE = ROOT / "benchmarks" / "data" / "step_suite.npz"
CONFIGS = ("panda_pair", "puma_beam_tight_limits", "both_sliding_bar",
           "ur5_pair_collision", "panda_pair_shelf")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=DEFAULT_OUT)
    args = ap.parse_args()
    calls: list[tuple[Any, ...]] = []
    source: list[str] = []
    original = _scale._lp
    label = ["step_suite"]

    def spy(M: np.ndarray, a: np.ndarray, g: np.ndarray, s_lo: float, s_hi: float) -> Any:
        out = original(M, a, g, s_lo, s_hi)
        calls.append((M.copy(), a.copy(), g.copy(), s_lo, s_hi, out))
        source.append(label[0])
        return out

    _scale._lp = spy
    try:
        for problem in load_suite(SUITE).problems:
            _scale.max_task_scale(problem)
        for config in CONFIGS:
            label[0] = config
            path = ROOT / "configs" / f"{config}.yaml"
            exp = build_experiment(load_config(path), str(path))
            run_experiment(exp, None, progress=False, plots=False)
            print(f"{config}: {source.count(config)} LPs")
    finally:
        _scale._lp = original
    shapes = np.array([c[0].shape for c in calls])
    found = [c[5] for c in calls]
    np.savez_compressed(
        args.out,
        M=np.concatenate([c[0].ravel() for c in calls]), M_shape=shapes,
        a=np.concatenate([c[1] for c in calls]), g=np.concatenate([c[2] for c in calls]),
        s_range=np.array([[c[3], c[4]] for c in calls]),
        done=np.array([f is not None for f in found]),
        ok=np.array([bool(f[0]) if f else False for f in found]),
        t=np.concatenate([f[1] if f else np.full(c[0].shape[1], np.nan)
                          for f, c in zip(found, calls, strict=True)]),
        s=np.array([f[2] if f else np.nan for f in found]),
        rows=np.array([",".join(map(str, f[3])) if f else "" for f in found]),
        source=np.array(source))
    print(f"wrote {len(calls)} LPs to {args.out}")


if __name__ == "__main__":
    main()
