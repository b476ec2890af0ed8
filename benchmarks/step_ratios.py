"""Two steps' costs as ratios, each pair timed call by call (interleaved).

1. **The step with torque rows against the same step without them**:
   ``configs/ur5_pair_heavy_bar.yaml`` on the states of one recorded rollout, one
   controller with torque limits on and one with them off, asked the same state in turn.
2. **The Case 2 support step against the Case 1 beam step**:
   ``configs/puma_beam_support.yaml`` and ``configs/puma_beam_limits.yaml``, each on the
   states of its own recorded rollout, call ``i`` of one beside call ``i`` of the other.

This machine alternates between fast and slow states for seconds at a time; alternating
the calls puts both under the same conditions, so the ratio is what the code costs
(:func:`outside_refs.interleaved`). Each row gives both medians [us], their ratio and the
median of the per-pair ratios.

Run it with ``python benchmarks/step_ratios.py [--samples 3000] [--json out.json]``
(about 20 s). It is a benchmark, not a test: it asserts nothing about speed.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from dualarm_qp.experiments.setup import Experiment

sys.path.insert(0, str(Path(__file__).resolve().parent))

# isort: split
from outside_refs import State, experiment, interleaved, record_states


def stepper(exp: Experiment, states: list[State]) -> Callable[[int], Any]:
    """Return ``f(i)``: a fresh controller of ``exp`` asked the ``i``-th state (cycling)."""
    ctrl = exp.controller()

    def step(i: int) -> Any:
        state, scale_max = states[i % len(states)]
        return ctrl.step(state, scale_max=scale_max)

    return step


def torque_rows(samples: int) -> dict[str, Any]:
    """The heavy-bar step with torque rows (a) and without them (b), on the same states."""
    exp = experiment("ur5_pair_heavy_bar")
    states, _ = record_states(exp)
    off = dataclasses.replace(exp, options=dataclasses.replace(exp.options,
                                                               torque_limits=False))
    return interleaved(stepper(exp, states), stepper(off, states), samples)


def support(samples: int) -> dict[str, Any]:
    """The Case 2 support step (a) and the Case 1 beam step (b)."""
    sup, beam = experiment("puma_beam_support"), experiment("puma_beam_limits")
    return interleaved(stepper(sup, record_states(sup)[0]),
                       stepper(beam, record_states(beam)[0]), samples)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=3000, help="timed pairs per row")
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args(argv)
    out = {"heavy bar, with torque rows / without": torque_rows(args.samples),
           "support step / beam step": support(args.samples)}
    for name, res in out.items():
        a, b = res["a"]["median_us"], res["b"]["median_us"]
        print(f"{name}: {a:.1f} us / {b:.1f} us = {a / b:.2f}x "
              f"(median of the pairs' ratios {res['ratio_median']:.2f}x)")
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(out, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
