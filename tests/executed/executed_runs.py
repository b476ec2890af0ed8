"""Config variants and an in-process runner for the executed-trajectory tests."""

from __future__ import annotations

import copy
import json
from pathlib import Path
from typing import Any

import yaml

from dualarm_qp.experiments.config import parse_config
from dualarm_qp.experiments.run import run_experiment
from dualarm_qp.experiments.setup import build_experiment
from dualarm_qp.solvers import available_solvers
from dualarm_qp.solvers.registry import solver_info

CONFIGS = Path(__file__).resolve().parents[2] / "configs"

#: Every available solver that claims hard limits.
HARD_SOLVERS = [n for n in available_solvers()
                if n not in ("reference", "fixed_grasp") and solver_info(n).hard_bounds]
#: The exact solvers that must complete the basic cases.
EXACT = ("nullspace", "qp:daqp")


def load(name: str) -> dict[str, Any]:
    with open(CONFIGS / f"{name}.yaml") as fh:
        return yaml.safe_load(fh)


def speed_up(data: dict[str, Any], factor: float) -> dict[str, Any]:
    """The object ``factor`` times faster over the same linear path."""
    data = copy.deepcopy(data)
    data["trajectory"]["velocity"] = [v * factor for v in data["trajectory"]["velocity"]]
    data["controller"]["duration"] = data["controller"]["duration"] / factor
    return data


def _with_duration(data: dict[str, Any], duration: float) -> dict[str, Any]:
    data = copy.deepcopy(data)
    data["controller"]["duration"] = duration
    return data


def with_policy(data: dict[str, Any], policy: str) -> dict[str, Any]:
    data = copy.deepcopy(data)
    data["controller"]["policy"] = policy
    return data


def _variants() -> dict[str, Any]:
    tight = load("puma_beam_tight_limits")
    out: dict[str, Any] = {name: (lambda n=name: load(n)) for name in (
        "puma_beam_limits", "puma_beam_fixed", "puma_beam_sliding_s7_100",
        "puma_beam_sliding_s7_1000", "curved_bar_waypoints", "puma_beam_fast",
        "puma_beam_leader_near_singular", "puma_beam_wrist_singular", "puma_beam_accel")}
    out["puma_beam_limits_x3"] = lambda: speed_up(load("puma_beam_limits"), 3.0)
    # Three times faster from rest, with the PUMA's acceleration limits: the first
    # samples cannot reach the path's speed, so the path is slowed (time is lost).
    out["puma_beam_limits_x3_accel"] = lambda: speed_up(load("puma_beam_accel"), 3.0)
    # The shipped file's path ends out of the leader's reach (the run is refused before
    # it starts); its first 13 s stay in reach and pass close to a singularity.
    out["puma_beam_leader_near_singular_13s"] = lambda: _with_duration(
        load("puma_beam_leader_near_singular"), 13.0)
    for policy in ("scale", "relax", "stop"):
        out[f"puma_beam_tight_limits_{policy}"] = lambda p=policy: with_policy(tight, p)
    return out


#: variant name -> zero-argument function returning the config dict.
VARIANTS = _variants()
#: Cases the exact solvers must complete (else the test fails: report, don't loosen).
MUST_COMPLETE = ("puma_beam_limits", "curved_bar_waypoints", "puma_beam_limits_x3",
                 "puma_beam_accel", "puma_beam_limits_x3_accel")


def build(variant: str, solver: str) -> Any:
    data = VARIANTS[variant]()
    return build_experiment(parse_config(data, variant), variant, solver=solver)


def run(variant: str, solver: str, out_dir: Path) -> tuple[Any, dict[str, Any]]:
    """Build and run in-process; return the experiment and the parsed summary.json."""
    exp = build(variant, solver)
    run_experiment(exp, out_dir, progress=False, plots=False)
    with open(out_dir / "summary.json") as fh:
        summary = json.load(fh)
    return exp, summary
