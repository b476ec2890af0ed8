"""Reproduce the paper's Sec. 4 example: the three PUMA beam cases and Figs. 5 and 6."""

from __future__ import annotations

from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from .config import load_config
from .outputs import write_json
from .plots import plot_compare
from .run import RunOutcome, run_experiment
from .setup import build_experiment

#: The paper's three cases: (label, config file name).
CASES = (
    ("a", "puma_beam_fixed.yaml"),
    ("b", "puma_beam_sliding_s7_100.yaml"),
    ("c", "puma_beam_sliding_s7_1000.yaml"),
)


#: What ``dualarm-qp bench`` compares when given no config: the beam task with speed
#: limits and the curved bar (the paper's own configs have no speed limits, where a
#: hard-limit solver's first, unlimited step tears the grasp closure open).
BENCH_CONFIGS = ("puma_beam_limits.yaml", "curved_bar_waypoints.yaml")


def bundled_config(name: str) -> Path:
    """Path of a configuration file shipped with the package."""
    return Path(str(resources.files("dualarm_qp") / "data" / name))


_JUMP_NOTE = ("first sample of (b), (c): the paper's step has no speed limit and Table 2 "
              "starts outside the ranges (docs/reproduction.md)")


@dataclass
class Reproduction:
    """Outcome of :func:`reproduce`: one run per case plus the paper's checks."""

    runs: dict[str, RunOutcome]
    checks: dict[str, Any]

    @property
    def ok(self) -> bool:
        """Whether every run completed."""
        return all(r.ok for r in self.runs.values())


def _joint3_excursion(outcome: RunOutcome) -> dict[str, float]:
    tr = outcome.result.trace
    margin = tr.margin_qf[:, 2]
    outside = margin < -1e-9
    return {
        "q3_min_deg": float(np.rad2deg(np.min(tr.q_f[:, 2]))),
        "q3_max_deg": float(np.rad2deg(np.max(tr.q_f[:, 2]))),
        "q3_margin_min_deg": float(np.rad2deg(np.min(margin))),
        "q3_samples_outside": int(np.count_nonzero(outside)),
        "q3_time_outside_s": float(np.count_nonzero(outside) * outcome.result.dt),
    }


def reproduce(out_dir: str | Path, *, config_dir: str | Path | None = None,
              progress: bool | None = None) -> Reproduction:
    """Run cases (a), (b), (c) and draw Fig. 5 (follower q3) and Fig. 6 (grasp).

    Parameters
    ----------
    out_dir : path
        Each case goes to ``out_dir/case_<x>/``; the figures and ``reproduce.json``
        to ``out_dir``.
    config_dir : path, optional
        Where the three YAML files are; default: the copies shipped with the package
        (identical to the repository's ``configs/``).
    progress : bool, optional
        Progress bars (default: when attached to a terminal).
    """
    out = Path(out_dir)
    runs: dict[str, RunOutcome] = {}
    for label, fname in CASES:
        path = Path(config_dir) / fname if config_dir is not None else bundled_config(fname)
        exp = build_experiment(load_config(path), str(path))
        runs[label] = run_experiment(exp, out / f"case_{label}", progress=progress)
    follower = build_experiment(load_config(
        Path(config_dir) / CASES[0][1] if config_dir is not None else bundled_config(CASES[0][1])
    )).task.follower
    traces = [(f"case ({k}) {r.summary['experiment']}", r.result.trace) for k, r in runs.items()]
    plot_compare(out / "fig5_joint3.png", traces, "q_f", joint=2,
                 limits=(follower.q_min[2], follower.q_max[2]), scale=180.0 / np.pi,
                 ylabel="follower q3 [deg]",
                 title="Fig. 5: follower joint 3 (dashed: its range)", note=_JUMP_NOTE)
    surface = build_experiment(load_config(
        Path(config_dir) / CASES[1][1] if config_dir is not None else bundled_config(CASES[1][1])
    )).task.surface
    plot_compare(out / "fig6_grasp.png", traces, "grasp", scale=1e3,
                 limits=(surface.sigma_min, surface.sigma_max),
                 ylabel="grasp r2_z [mm]", title="Fig. 6: follower grasp position "
                 "(dashed: the grasp range of Eq. 3)", note=_JUMP_NOTE)
    checks: dict[str, Any] = {k: _joint3_excursion(r) for k, r in runs.items()}
    for k in ("b", "c"):
        g = runs[k].result.trace.grasp
        checks[k]["grasp_start_mm"] = float(g[0] * 1e3)
        checks[k]["grasp_end_mm"] = float(g[-1] * 1e3)
        checks[k]["grasp_travel_first_10_steps_mm"] = float(abs(g[min(10, len(g) - 1)] - g[0])
                                                            * 1e3)
    checks["claims"] = {
        "case_a_leaves_joint3_range": checks["a"]["q3_samples_outside"] > 0,
        "case_b_joint3_inside": checks["b"]["q3_samples_outside"] == 0,
        "case_c_joint3_inside": checks["c"]["q3_samples_outside"] == 0,
        "case_c_moves_less_at_start": checks["c"]["grasp_travel_first_10_steps_mm"]
        < checks["b"]["grasp_travel_first_10_steps_mm"],
    }
    write_json(out / "reproduce.json", {
        "cases": {k: r.summary for k, r in runs.items()},
        "checks": checks,
        "figures": ["fig5_joint3.png", "fig6_grasp.png"],
    })
    return Reproduction(runs, checks)
