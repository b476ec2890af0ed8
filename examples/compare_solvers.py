"""Compare two step solvers on one task.

Runs configs/puma_beam_limits.yaml (two PUMA 560 arms carrying a beam, with hard joint
and sliding speed limits) once with the exact ``nullspace`` solver and once with the
QP through the ``daqp`` backend, and prints, for each, whether the run completed, the
worst realised speed ratio (largest |recorded speed| / speed limit over both arms and
the grasp; at most 1 when every limit was kept) and the median time of a controller
step. ``dualarm-qp solvers`` lists every solver name; ``dualarm-qp bench`` runs them
all and writes a full report.

Run it with ``python examples/compare_solvers.py`` (two runs of 500 samples).
"""

import math
from pathlib import Path

import dualarm_qp as dq

CONFIG = Path(__file__).resolve().parents[1] / "configs" / "puma_beam_limits.yaml"
SOLVERS = ["nullspace", "qp:daqp"]

cfg = dq.load_config(CONFIG)
print(f"{'solver':<10} {'completed':<9} {'speed ratio':>11} {'step median':>12}")
for name in SOLVERS:
    # The same task and settings; only the solver differs (like --solver on the CLI).
    exp = dq.build_experiment(cfg, str(CONFIG), solver=name)
    # No output folder: nothing is written, the summary is returned.
    outcome = dq.run_experiment(exp, None, progress=False)
    speed = max((r.speed_ratio for r in outcome.result.realised.values()
                 if not math.isnan(r.speed_ratio)), default=math.nan)
    step_ms = outcome.summary["step_time_median_s"] * 1e3
    print(f"{name:<10} {outcome.result.completed!s:<9} {speed:>11.3f} {step_ms:>9.3f} ms")
