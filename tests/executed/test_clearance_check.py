"""The independent clearance check on recorded runs, and that it can fail.

The beam task with a ball in the follower's way (executed_runs.SCENE_VARIANTS): with
collision avoidance on, every pair stays at or above d_s - allowance and the rows bind
(the nearest pair comes within 0.5 mm of d_s); with it off, the check finds link2 inside
the ball. Doctored copies of a good CSV are caught. Other arms and shapes: a DH table
that is not the preset (its own oracle path), and two UR5s with a box object and a box
obstacle (the URDF oracle, box distances).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from clearance_check import (
    check_clearance,
    check_columns,
    check_kept,
    penetrations,
    recompute,
)
from csv_check import read_trajectory, write_trajectory
from executed_runs import BALL, load, merged, run, with_obstacles

from dualarm_qp.collision.settings import CLEARANCE_ALLOWANCE
from dualarm_qp.experiments.config import parse_config
from dualarm_qp.experiments.run import run_experiment
from dualarm_qp.experiments.setup import build_experiment
from dualarm_qp.kinematics.robots import example_robots_dir

#: The PUMA 560 of Table 1 as a plain DH table (mm, deg) and the preset's radii (mm).
PUMA_DH = [[0, -90, 0], [431.8, 0, 149.09], [-20.32, 90, 0], [0, -90, 433.07], [0, 90, 0],
           [0, 0, 56.25]]
PUMA_RADII = [120, 100, 80, 60, 50, 40]


def _run_data(data: dict, tmp: Path, solver: str = "nullspace"):
    exp = build_experiment(parse_config(data, "case"), "case", solver=solver)
    run_experiment(exp, tmp, progress=False, plots=False)
    summary = json.loads((tmp / "summary.json").read_text())
    return exp, summary, read_trajectory(tmp / "trajectory.csv")


@pytest.fixture(scope="module")
def ball(tmp_path_factory: pytest.TempPathFactory):
    out = tmp_path_factory.mktemp("ball")
    exp, summary = run("puma_beam_ball", "nullspace", out)
    return exp, summary, read_trajectory(out / "trajectory.csv")


@pytest.fixture(scope="module")
def ball_off(tmp_path_factory: pytest.TempPathFactory):
    out = tmp_path_factory.mktemp("ball_off")
    exp, summary = run("puma_beam_ball_off", "nullspace", out)
    return exp, summary, read_trajectory(out / "trajectory.csv")


def test_enabled_run_keeps_the_clearance_and_the_rows_bind(ball, ball_off) -> None:
    exp, summary, traj = ball
    assert summary["completed"], summary["failure"]
    assert check_clearance(traj, exp) == []
    rec = recompute(traj, exp)
    d_s = exp.task.scene.settings.safety_distance
    assert exp.task.scene.settings.enabled
    assert rec.distance.min() >= d_s - CLEARANCE_ALLOWANCE
    # Not a vacuous pass: the ball is in the way (the same run without the rows enters
    # it) and the rows bind (the nearest pair reaches d_s).
    nearest, pair = rec.nearest()
    k = int(np.argmin(nearest))
    assert nearest[k] < d_s + 0.5e-3 and pair[k] == "follower.link2 - ball"
    off = recompute(ball_off[2], ball_off[0])
    assert off.distance.min() < 0.0
    assert np.max(np.abs(traj["grasp"] - ball_off[2]["grasp"])) > 0.05  # it slid round


def test_disabled_run_penetration_is_found(ball_off) -> None:
    exp, summary, traj = ball_off
    assert summary["completed"]
    assert not exp.task.scene.settings.enabled
    rec = recompute(traj, exp)
    found = penetrations(rec)
    assert len(found) == 1 and found[0].startswith("penetration follower.link2 - ball:")
    assert rec.distance[:, rec.pairs.index("follower.link2 - ball")].min() < -0.01
    # The CSV still records it faithfully, and only an enabled run would have failed.
    assert check_columns(traj, rec) == []
    assert check_clearance(traj, exp) == []
    kept = check_kept(rec, exp.task.scene.settings.safety_distance)
    assert kept and kept[0].startswith("clearance follower.link2 - ball:")
    reported = summary["realised_limits"]["clearance"]
    assert reported["penetration"] and not reported["enforced"]
    assert abs(reported["min_m"] - rec.distance.min()) < 1e-9


def _copy(traj: dict) -> dict:
    return {k: v.copy() for k, v in traj.items()}


def test_a_clearance_column_off_by_2e_6_is_caught(ball, tmp_path: Path) -> None:
    exp, _summary, traj = ball
    rec = recompute(traj, exp)
    k = len(traj["t"]) // 2
    for column in ("clearance_obstacles", "clearance_arm_arm"):
        bad = _copy(traj)
        bad[column][k] += 2e-6
        write_trajectory(tmp_path / "bad.csv", bad)
        problems = check_columns(read_trajectory(tmp_path / "bad.csv"), rec)
        assert len(problems) == 1 and problems[0].startswith(f"{column}: 1 rows")
        assert f"worst row {k} " in problems[0]
        near = _copy(traj)
        near[column][k] += 5e-7
        assert check_columns(near, rec) == []


def test_a_wrong_nearest_pair_or_a_missing_column_is_caught(ball) -> None:
    exp, _summary, traj = ball
    rec = recompute(traj, exp)
    bad = _copy(traj)
    bad["clearance_pair"][3] = "leader.link1 - follower.link1"
    problems = check_columns(bad, rec)
    assert len(problems) == 1 and problems[0].startswith("clearance_pair: 1 rows")
    gone = _copy(traj)
    del gone["clearance_obstacles"]
    assert check_columns(gone, rec) == ["missing column clearance_obstacles"]


def test_joints_moved_into_the_ball_are_caught(ball, ball_off) -> None:
    """Row k of the good run given the joints of the penetrating run's deepest row."""
    exp, _summary, traj = ball
    off = recompute(ball_off[2], ball_off[0])
    deep = int(np.argmin(off.distance.min(axis=1)))
    bad = _copy(traj)
    k = deep
    for c in [f"qf{i}" for i in range(1, 7)] + [f"ql{i}" for i in range(1, 7)]:
        bad[c][k] = ball_off[2][c][deep]
    problems = check_clearance(bad, exp)
    assert any(p.startswith("clearance follower.link2 - ball: 1 rows") for p in problems)
    assert any(p.startswith("clearance_obstacles: 1 rows") for p in problems)


def test_a_dh_table_arm_uses_the_general_oracle(ball, tmp_path: Path) -> None:
    """The follower as a DH table with the preset's radii: its own oracle path (rows
    from the table) gives the same distances as the preset's run, and keeps them."""
    data = with_obstacles(load("puma_beam_limits"), [BALL], enabled=True, duration=6.0)
    del data["follower"]["preset"]
    data["follower"].update(dh={"rows": PUMA_DH}, link_radius=PUMA_RADII)
    exp, summary, traj = _run_data(data, tmp_path)
    assert summary["completed"], summary["failure"]
    assert exp.task.follower.source != "preset:puma560"
    assert check_clearance(traj, exp) == []
    mine = recompute(traj, exp)
    preset = recompute(ball[2], ball[0])
    assert mine.pairs == preset.pairs
    assert np.max(np.abs(mine.distance - preset.distance)) < 1e-6


needs_robots = pytest.mark.skipif(example_robots_dir() is None,
                                  reason="example-robot-data is not installed")

#: Two UR5s carrying a bar (both grasps slide): the bar as a box in the object frame
#: (x down into its top face, z along it; mm) and a crate.
BAR = {"shape": {"box": {"size": [40, 40, 900]}, "pose": {"position": [20, 0, 400]}}}
CRATE_BELOW = {"name": "crate", "box": {"size": [100, 100, 100]},
               "pose": {"position": [700, 0, 150]}}
CRATE_IN_THE_WAY = {"name": "crate", "box": {"size": [100, 100, 100]},
                    "pose": {"position": [700, 200, 300], "rpy": [0, 0, 20]}}


@needs_robots
@pytest.mark.slow
def test_urdf_arms_with_boxes(tmp_path: Path) -> None:
    """Enabled, a crate under the bar: every pair (boxes included) recomputed and kept."""
    data = merged(load("both_sliding_bar"), {"object": BAR})
    data = with_obstacles(data, [CRATE_BELOW], enabled=True)
    exp, summary, traj = _run_data(data, tmp_path)
    assert summary["completed"], summary["failure"]
    rec = recompute(traj, exp)
    assert "object - crate" in rec.pairs and any(p.endswith("- object") for p in rec.pairs)
    assert check_clearance(traj, exp) == []
    assert rec.group_min("obstacle").min() < 0.1     # the crate is within d_i


@needs_robots
@pytest.mark.slow
def test_urdf_arms_bar_through_a_box_is_found(tmp_path: Path) -> None:
    """Disabled, a crate the bar's path enters: the check finds the bar in the crate."""
    data = merged(load("both_sliding_bar"), {"object": BAR})
    data = with_obstacles(data, [CRATE_IN_THE_WAY], enabled=False)
    exp, summary, traj = _run_data(data, tmp_path)
    rec = recompute(traj, exp)
    assert check_columns(traj, rec) == []
    found = penetrations(rec)
    assert any(p.startswith("penetration object - crate:") for p in found), found
    assert summary["realised_limits"]["clearance"]["penetration"]


@needs_robots
@pytest.mark.slow
def test_seven_joint_arms_self_pairs(tmp_path: Path) -> None:
    """Two Pandas (7 joints: self pairs, the clearance_self column), collisions on."""
    data = merged(load("panda_pair"), {"controller": {"duration": 1.0}})
    data = with_obstacles(data, [{"name": "lamp", "sphere": {"radius": 50},
                                  "pose": {"position": [500, 300, 600]}}], enabled=True)
    exp, summary, traj = _run_data(data, tmp_path)
    assert summary["completed"], summary["failure"]
    rec = recompute(traj, exp)
    assert "self" in rec.groups and "clearance_self" in traj
    assert check_clearance(traj, exp) == []
