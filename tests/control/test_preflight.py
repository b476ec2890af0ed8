"""The path is checked against the arms' reach at its waypoints before a run starts."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import yaml

from dualarm_qp.control.preflight import _reach, checkpoints, unreachable_waypoint
from dualarm_qp.control.rollout import rollout
from dualarm_qp.experiments import build_experiment, load_config
from dualarm_qp.experiments.config import parse_config
from dualarm_qp.kinematics.robots import example_robot_arm
from dualarm_qp.se3 import pose_error

CONFIGS = Path(__file__).resolve().parents[2] / "configs"


def waypoint_config(far_mm: float) -> dict:
    data = yaml.safe_load((CONFIGS / "curved_bar_waypoints.yaml").read_text())
    data["trajectory"]["waypoints"][1]["pose"]["position"][1] += far_mm
    return data


def test_a_path_ending_out_of_reach_is_refused_before_the_first_sample() -> None:
    exp = build_experiment(load_config(CONFIGS / "puma_beam_leader_near_singular.yaml"))
    res = rollout(exp.controller(), exp.initial, duration=exp.duration, limits=exp.limits)
    assert res.failure is not None and res.failure.criterion == "unreachable"
    assert len(res.trace) == 0
    assert "leader cannot reach the end of the path" in res.message
    assert "t = 15.5 s" in res.message
    assert res.failure.amount > 0.01  # 26 mm short, not a rounding miss
    # The same path cut before it leaves the leader's reach passes the check.
    assert unreachable_waypoint(exp.task, exp.initial, 13.0, within_ranges=True) is None


def test_a_waypoint_out_of_reach_is_named() -> None:
    exp = build_experiment(parse_config(waypoint_config(far_mm=2000.0), "far"), "far")
    res = rollout(exp.controller(), exp.initial, duration=exp.duration, limits=exp.limits)
    assert res.failure is not None and res.failure.criterion == "unreachable"
    assert "waypoint 1 of the path" in res.message and "t = 4 s" in res.message
    assert res.summary()["unreachable"] == {"arm": "leader",
                                            "waypoint": "waypoint 1 of the path", "t_s": 4.0}


def test_checkpoints_are_the_waypoints_after_the_start() -> None:
    exp = build_experiment(load_config(CONFIGS / "curved_bar_waypoints.yaml"))
    assert checkpoints(exp.task, 0.0, 8.0) == [(4.0, "waypoint 1 of the path"),
                                               (8.0, "waypoint 2 of the path")]
    beam = build_experiment(load_config(CONFIGS / "puma_beam_limits.yaml"))
    assert checkpoints(beam.task, 0.0, 15.5) == [(15.5, "the end of the path")]


@pytest.mark.parametrize("name", ["puma_beam_limits", "curved_bar_waypoints",
                                  "puma_beam_support"])
def test_reachable_paths_pass(name: str) -> None:
    exp = build_experiment(load_config(CONFIGS / f"{name}.yaml"))
    t_end = exp.initial.t + exp.duration
    assert unreachable_waypoint(exp.task, exp.initial, t_end, within_ranges=True) is None


@pytest.mark.slow
def test_the_command_line_exits_1_with_the_criterion(tmp_path: Path) -> None:
    cfg = tmp_path / "far.yaml"
    cfg.write_text(yaml.safe_dump(waypoint_config(far_mm=2000.0)))
    out = tmp_path / "out"
    proc = subprocess.run([sys.executable, "-m", "dualarm_qp.cli", "run", str(cfg), "--out",
                           str(out), "--no-plots", "--quiet"], capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 1, proc.stderr
    assert "cannot reach waypoint 1 of the path" in proc.stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["failure"]["criterion"] == "unreachable"
    assert summary["samples"] == 0
    header = (out / "trajectory.csv").read_text().splitlines()
    assert len(header) == 1 and header[0].startswith("t,")



def test_a_seed_at_an_exact_singularity_is_nudged_off_it() -> None:
    """A UR5 stretched (elbow at 0, an exact singularity) asked to move along the direction
    it lost: from the exact seed the solve has no first-order descent (here it stalls
    where it starts in both directions; elsewhere rounding may let it escape), and the
    nudged seed reaches the one direction inside the workspace."""
    arm = example_robot_arm("ur5", "base_link", "tool0")
    seed = np.deg2rad([-15.8, -101.1, 0.0, -108.4, -90.0, -105.8])
    u = np.linalg.svd(arm.jacobian(seed))[0][:, -1]
    reached = []
    for sign in (1.0, -1.0):
        T = arm.fk(seed)
        T[:3, :3] = pin.exp3(sign * 0.02 * u[3:]) @ T[:3, :3]
        T[:3, 3] += sign * 0.02 * u[:3]
        found = _reach(arm, T, seed, False)
        if isinstance(found, np.ndarray):
            np.testing.assert_allclose(pose_error(T, arm.fk(found)), 0.0, atol=1e-6)
            reached.append(sign)
    assert len(reached) == 1


def test_the_message_says_within_the_ranges_only_when_they_were_kept() -> None:
    exp = build_experiment(load_config(CONFIGS / "puma_beam_leader_near_singular.yaml"))
    kept = unreachable_waypoint(exp.task, exp.initial, 15.5, within_ranges=True)
    free = unreachable_waypoint(exp.task, exp.initial, 15.5, within_ranges=False)
    assert kept is not None and free is not None  # out of reach either way: too far
    assert "cannot reach the end of the path (t = 15.5 s) within its joint ranges:" in kept.message
    assert "cannot reach the end of the path (t = 15.5 s): the closest" in free.message
