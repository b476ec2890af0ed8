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
#: Every available solver that keeps general rows (collision avoidance).
ROW_SOLVERS = [n for n in available_solvers() if solver_info(n).takes_rows]
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


def merged(data: dict[str, Any], extra: dict[str, Any]) -> dict[str, Any]:
    """``data`` with ``extra`` merged over it, key by key (nested mappings merged too)."""
    out = copy.deepcopy(data)
    for key, value in extra.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = merged(out[key], value)
        else:
            out[key] = copy.deepcopy(value)
    return out


# Collision set-ups on the paper's beam task (mm): obstacles in the follower's way.
#: A ball the follower's upper arm (link2) would pass through in the first 6 s; with
#: collision avoidance the sliding grasp takes the arm round it at d_s (the rows bind).
BALL = {"name": "ball", "sphere": {"radius": 50}, "pose": {"position": [155, 855, -210]}}
#: A ball under the follower's elbow: no slide avoids it; the task stops near t = 4.1 s.
BALL_BLOCKING = {"name": "ball", "sphere": {"radius": 50},
                 "pose": {"position": [155, 1005, -350]}}
#: A pillar the follower's link2 comes within d_s of near t = 9.6 s: the task stops.
PILLAR = {"name": "pillar", "capsule": {"radius": 50, "length": 1200},
          "pose": {"position": [450, 1230, 0]}}
#: The pillar moved 115 mm along x: the task completes; within d_i the rows slow link2's
#: approach (it ends 22 mm from the pillar) and the grasp ends 13 mm short of its run
#: without the pillar.
PILLAR_CLEAR = {**PILLAR, "pose": {"position": [565, 1230, 0]}}


def with_obstacles(data: dict[str, Any], obstacles: list[dict[str, Any]], *, enabled: bool,
                   duration: float | None = None) -> dict[str, Any]:
    """``data`` with these obstacles and collision avoidance on or off (mm, s)."""
    extra: dict[str, Any] = {"scene": {"obstacles": obstacles},
                             "collision": {"enabled": enabled}}
    if duration is not None:
        extra["controller"] = {"duration": duration}
    return merged(data, extra)


def collision_enabled(data: dict[str, Any]) -> bool:
    """Whether a config dict asks for collision avoidance (its solver must take rows)."""
    return bool((data.get("collision") or {}).get("enabled", False))


#: Collision set-ups (variant name -> config) of the beam task.
SCENE_VARIANTS = {
    "puma_beam_ball": lambda: with_obstacles(load("puma_beam_limits"), [BALL], enabled=True,
                                             duration=6.0),
    "puma_beam_ball_off": lambda: with_obstacles(load("puma_beam_limits"), [BALL],
                                                 enabled=False, duration=6.0),
    "puma_beam_ball_blocked": lambda: with_obstacles(load("puma_beam_limits"), [BALL_BLOCKING],
                                                     enabled=True, duration=6.0),
    "puma_beam_pillar": lambda: with_obstacles(load("puma_beam_limits"), [PILLAR],
                                               enabled=True),
    "puma_beam_pillar_clear": lambda: with_obstacles(load("puma_beam_limits"), [PILLAR_CLEAR],
                                                     enabled=True),
}


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
    # With a scene: the recorded clearance is checked too (clearance_check). The ball
    # set-ups with collisions on run with every solver in test_collision_solvers.py.
    out["puma_beam_ball_off"] = SCENE_VARIANTS["puma_beam_ball_off"]
    out["puma_beam_pillar"] = SCENE_VARIANTS["puma_beam_pillar"]
    out["puma_beam_pillar_clear"] = SCENE_VARIANTS["puma_beam_pillar_clear"]
    return out


#: variant name -> zero-argument function returning the config dict.
VARIANTS = _variants()
#: Cases the exact solvers must complete (else the test fails: report, don't loosen).
MUST_COMPLETE = ("puma_beam_limits", "curved_bar_waypoints", "puma_beam_limits_x3",
                 "puma_beam_accel", "puma_beam_limits_x3_accel", "puma_beam_pillar_clear")


def build(variant: str, solver: str) -> Any:
    data = {**VARIANTS, **SCENE_VARIANTS}[variant]()
    return build_experiment(parse_config(data, variant), variant, solver=solver)


def run(variant: str, solver: str, out_dir: Path) -> tuple[Any, dict[str, Any]]:
    """Build and run in-process; return the experiment and the parsed summary.json."""
    exp = build(variant, solver)
    run_experiment(exp, out_dir, progress=False, plots=False)
    with open(out_dir / "summary.json") as fh:
        summary = json.load(fh)
    return exp, summary
