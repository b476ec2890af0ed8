"""Our PUMA step and Panda-shelf step against pink's UR5 step, timed interleaved.

The two ratios of the speed targets that are stated against pink (``outside_refs.py``
sections 5 and 7), alone: each configuration's recorded rollout states are replayed
through a controller, call by call alternating with pink's UR5 step (daqp), and the
median of the per-pair ratios is printed with both medians [us].

``--tree PATH`` takes the benchmark helpers (``outside_refs.py``) of another checkout,
so that an earlier commit, installed in its own environment, is measured by the same
code: run ``OLD/.venv/bin/python benchmarks/step_vs_pink.py --tree OLD`` and
``.venv/bin/python benchmarks/step_vs_pink.py`` alternately, and compare the ratios
(each timed against pink in its own process, in the same machine state).

Run it with ``python benchmarks/step_vs_pink.py [--tree PATH] [--samples 1000]``
(about 30 s; needs pink: ``pip install "pin-pink>=3"``). A benchmark, not a test.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

CONFIGS = ("puma_beam_limits", "panda_pair_shelf")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tree", type=Path, default=Path(__file__).resolve().parents[1],
                    help="checkout whose benchmarks/outside_refs.py is used")
    ap.add_argument("--samples", type=int, default=1000, help="pairs of calls per config")
    args = ap.parse_args(argv)
    sys.path.insert(0, str(args.tree / "benchmarks"))
    import outside_refs as refs  # the tree's own helpers

    pink: dict[str, Any] = {}
    refs.pink_ur5(2000, pink)
    ur5_step = pink.get("_daqp_step")
    if ur5_step is None:
        print("pink is not installed: nothing to compare with", file=sys.stderr)
        return 1
    out: dict[str, Any] = {"tree": str(args.tree)}
    for name in CONFIGS:
        exp = refs.experiment(name)
        states, _ = refs.record_states(exp)
        ctrl = exp.controller()

        def ours(i: int, ctrl: Any = ctrl, states: list[Any] = states) -> None:
            state, scale_max = states[i % len(states)]
            ctrl.step(state, scale_max=scale_max)

        r = refs.interleaved(ours, ur5_step, args.samples)
        out[name] = {"ratio": round(r["ratio_median"], 3),
                     "ours_us": round(r["a"]["median_us"], 1),
                     "pink_us": round(r["b"]["median_us"], 1)}
        print(f"{name:20s} our step / pink's UR5 step {out[name]['ratio']:.3f}x "
              f"(medians {out[name]['ours_us']} us and {out[name]['pink_us']} us)")
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
