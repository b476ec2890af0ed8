"""Collision set-ups the command line refuses (exit 2) or runs and fails (exit 1).

Each file is the paper's beam task (configs/puma_beam_limits.yaml) with extra keys,
written to a temporary folder and run through ``dualarm_qp.cli.main`` (its return
value is the process's exit code).

* exit 2, naming the key: ``xi dt > d_i - d_s`` (``collision.approach_speed_max``), an
  excluded name that is no body (``collision.exclude``, with the valid bodies), a DH
  table without capsule radii (``follower.link_radius``; the PUMA preset has defaults);
* exit 1: a path D(t) that runs the object into a box (criterion ``path_collision``,
  the obstacle and the first t within d_s, checked here with the tests' own distance),
  a start closer than d_s (less the allowance) to a ball, refused before the run
  (criterion ``collision``, naming the pair and its distance), and a pillar that blocks
  the task (criterion ``collision``, naming the pair).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import yaml
from clearance_check import check_clearance, recompute
from clearance_oracle import segment_box
from csv_check import read_trajectory
from executed_runs import PILLAR, load, merged, with_obstacles

from dualarm_qp.cli import main
from dualarm_qp.experiments.config import parse_config
from dualarm_qp.experiments.setup import build_experiment

#: The PUMA 560 of Table 1 as a plain DH table (mm, deg).
PUMA_DH = [[0, -90, 0], [431.8, 0, 149.09], [-20.32, 90, 0], [0, -90, 433.07], [0, 90, 0],
           [0, 0, 56.25]]


def _run(tmp_path: Path, data: dict, capsys: pytest.CaptureFixture[str],
         *extra: str) -> tuple[int, str, Path]:
    config = tmp_path / "case.yaml"
    config.write_text(yaml.safe_dump(data))
    out = tmp_path / "out"
    code = main(["run", str(config), "--out", str(out), "--no-plots", "--quiet", *extra])
    return code, capsys.readouterr().err, out


def _beam(extra: dict, duration: float = 0.31) -> dict:
    return merged(load("puma_beam_limits"),
                  merged({"controller": {"duration": duration}}, extra))


@pytest.mark.parametrize("where", ["file", "option"])
def test_a_boxes_only_solver_with_collision_rows_is_refused_naming_where_it_was_chosen(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], where: str) -> None:
    """sns takes boxes only: exit 2 naming the file (and ``solver.name`` if it chose sns)."""
    data = _beam({"collision": {"enabled": True}})
    extra: tuple[str, ...] = ()
    if where == "file":
        data["solver"] = {"name": "sns"}
    else:
        extra = ("--solver", "sns")
    got, err, out = _run(tmp_path, data, capsys, *extra)
    assert got == 2, err
    assert "case.yaml" in err and "collision" in err and "nullspace" in err
    assert ("key 'solver.name'" in err) is (where == "file") and "solver 'sns'" in err
    assert not out.exists() or not (out / "summary.json").exists()


def test_pairs_overlapping_at_the_start_are_left_out_with_a_warning(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Fat leader capsules overlap the follower's: those pairs are named, never silent."""
    data = _beam({"collision": {"enabled": True},
                  "leader": {"link_radius": [1400, 100, 80, 60, 50, 40]}})
    got, err, out = _run(tmp_path, data, capsys)
    assert got == 0, err
    summary = json.loads((out / "summary.json").read_text())
    left_out = [e["pair"] for e in summary["collision"]["excluded"]
                if e["why"].startswith("overlapping at the start")]
    assert left_out and all(p.startswith("leader.link1 - ") for p in left_out)
    warning = [w for w in summary["warnings"] if "overlap at the start" in w]
    assert len(warning) == 1 and all(p in warning[0] for p in left_out)


@pytest.mark.parametrize(("xi", "code"), [(2581.0, 2), (2580.0, 0)])
def test_an_approach_speed_that_crosses_the_band_in_one_step_is_refused(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], xi: float, code: int) -> None:
    """dt = 31 ms, d_i - d_s = 80 mm: xi dt > 80 mm above xi = 2580.6 mm/s."""
    got, err, out = _run(tmp_path, _beam({"collision": {"enabled": True,
                                                        "approach_speed_max": xi}}), capsys)
    assert got == code, err
    if code == 2:
        assert "collision.approach_speed_max" in err and "case.yaml" in err
        assert not out.exists() or not (out / "summary.json").exists()


def test_a_bad_exclude_name_is_refused_with_the_valid_bodies(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    data = with_obstacles(_beam({}), [PILLAR], enabled=True)
    data["collision"]["exclude"] = [["follower.link2", "pilar"]]
    code, err, _ = _run(tmp_path, data, capsys)
    assert code == 2, err
    assert "collision.exclude" in err and "'pilar'" in err
    for body in ("pillar", "follower.link2", "leader.link6"):
        assert body in err
    # The right name runs, and the pair is reported as excluded.
    data["collision"]["exclude"] = [["follower.link2", "pillar"]]
    code, err, out = _run(tmp_path, data, capsys, "--force")
    assert code == 0, err
    excluded = json.loads((out / "summary.json").read_text())["collision"]["excluded"]
    assert {"pair": "follower.link2 - pillar", "why": "excluded in the set-up"} in excluded


def test_an_obstacle_through_an_arm_at_the_start_is_refused(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    # The follower's shoulder stands at (300, 1380, 0) mm: a post there overlaps it.
    post = {"name": "post", "capsule": {"radius": 50, "length": 1200},
            "pose": {"position": [300, 1380, 0]}}
    for enabled in (True, False):  # the scene is wrong whether or not it is avoided
        code, err, out = _run(tmp_path, with_obstacles(_beam({}), [post], enabled=enabled),
                              capsys, "--force")
        assert code == 2, err
        assert "scene.obstacles.0.pose" in err and "'post' overlaps follower.link1" in err
        assert not (out / "summary.json").exists()


def test_a_dh_arm_without_link_radius_is_refused(tmp_path: Path,
                                                 capsys: pytest.CaptureFixture[str]) -> None:
    data = _beam({"collision": {"enabled": True}})
    del data["follower"]["preset"]
    data["follower"]["dh"] = {"rows": PUMA_DH}
    code, err, _ = _run(tmp_path, data, capsys)
    assert code == 2, err
    assert "follower.link_radius" in err
    data["follower"]["link_radius"] = [120, 100, 80]      # one per link: 6
    code, err, _ = _run(tmp_path, data, capsys, "--force")
    assert code == 2 and "follower.link_radius" in err and "6" in err
    # The PUMA preset has default radii; the same table with radii runs.
    data["follower"]["link_radius"] = [120, 100, 80, 60, 50, 40]
    code, err, _ = _run(tmp_path, data, capsys, "--force")
    assert code == 0, err
    code, err, _ = _run(tmp_path, _beam({"collision": {"enabled": True}}), capsys, "--force")
    assert code == 0, err


#: The beam as a capsule along the object's z axis (500 mm), and a crate across D(t).
BEAM_SHAPE = {"shape": {"capsule": {"radius": 25, "length": 500},
                        "pose": {"position": [0, 0, 250]}}}
CRATE = {"name": "crate", "box": {"size": [50, 50, 50]}, "pose": {"position": [250, 800, 260]}}


def test_a_path_through_an_obstacle_is_refused_before_the_run(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    data = with_obstacles(merged(load("puma_beam_limits"), {"object": BEAM_SHAPE}), [CRATE],
                          enabled=True)
    code, err, out = _run(tmp_path, data, capsys)
    assert code == 1, err
    summary = json.loads((out / "summary.json").read_text())
    failure = summary["failure"]
    assert failure["criterion"] == "path_collision"
    assert summary["path_collision"]["obstacle"] == "crate" and "'crate'" in failure["message"]
    assert summary["samples"] == 0 and len(read_trajectory(out / "trajectory.csv")["t"]) == 0
    # Where: the first sample of D(t) (every dt) at which the beam comes within d_s of
    # the crate, by the tests' own distance.
    exp = build_experiment(parse_config(data, "case"), "case")
    d_s = exp.task.scene.settings.safety_distance
    dt = exp.options.dt
    times = np.arange(0, round(exp.duration / dt) + 1) * dt
    poses = np.array([exp.task.trajectory.pose(float(t)) for t in times])
    a = poses @ np.array([0.0, 0.0, 0.0, 1.0])
    b = poses @ np.array([0.0, 0.0, 0.5, 1.0])
    box_R = np.tile(np.eye(3), (len(times), 1, 1))
    gap = segment_box(a[:, :3], b[:, :3], np.tile([0.25, 0.8, 0.26], (len(times), 1)), box_R,
                      np.tile([0.025] * 3, (len(times), 1))) - 0.025
    first = int(np.flatnonzero(gap < d_s)[0])
    assert gap.min() < 0.0                               # the path runs through it
    assert abs(failure["t_s"] - times[first]) < 1e-9, (failure["t_s"], times[first])
    assert abs(summary["path_collision"]["distance_m"] - gap[first]) < 1e-9
    assert f"t = {times[first]:.4g} s" in failure["message"]


def test_a_blocked_task_fails_naming_the_pair(tmp_path: Path,
                                              capsys: pytest.CaptureFixture[str]) -> None:
    data = with_obstacles(load("puma_beam_limits"), [PILLAR], enabled=True)
    code, err, out = _run(tmp_path, data, capsys)
    assert code == 1, err
    failure = json.loads((out / "summary.json").read_text())["failure"]
    assert failure["criterion"] == "collision"
    assert "follower.link2 - pillar" in failure["message"]
    assert 9.0 < failure["t_s"] < 10.0
    # It stopped short of the pillar: the record keeps d_s - allowance.
    exp = build_experiment(parse_config(data, "case"), "case")
    assert check_clearance(read_trajectory(out / "trajectory.csv"), exp) == []


def test_a_start_within_the_safety_distance_is_refused_before_the_run(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A ball 18 mm from the follower's elbow (link3) at the start, d_s = 20 mm: refused
    before the first sample (as a torque beyond its limit at the start is), naming the
    pair and its distance, not run to the end and failed at sample 0 afterwards."""
    ball = {"name": "ball", "sphere": {"radius": 50}, "pose": {"position": [155, 1145, -210]}}
    data = with_obstacles(_beam({}, duration=3.0), [ball], enabled=True)
    # The ball also overlaps the upper arm (link2), which would refuse the scene itself.
    data["collision"]["exclude"] = [["follower.link2", "ball"]]
    code, err, out = _run(tmp_path, data, capsys)
    assert code == 1, err
    summary = json.loads((out / "summary.json").read_text())
    failure = summary["failure"]
    assert failure["criterion"] == "collision" and summary["samples"] == 0
    assert len(read_trajectory(out / "trajectory.csv")["t"]) == 0
    # The pair and its distance, by the tests' own distance at the initial joints.
    exp = build_experiment(parse_config(data, "case"), "case")
    start = {"t": np.zeros(1), "grasp": np.array([exp.initial.sigma])}
    for prefix, q in (("ql", exp.initial.q_l), ("qf", exp.initial.q_f)):
        start.update({f"{prefix}{i + 1}": q[i:i + 1] for i in range(q.size)})
    rec = recompute(start, exp)
    d = dict(zip(rec.pairs, rec.distance[0], strict=True))["follower.link3 - ball"]
    assert 0.0 < d < 0.019 and min(rec.distance[0]) == d
    at_start = summary["collision_at_start"]
    assert at_start["pair"] == "follower.link3 - ball"
    assert abs(at_start["distance_m"] - d) < 1e-9 and at_start["safety_distance_m"] == 0.02
    assert failure["message"].startswith("before the run: collision pair follower.link3 - "
                                         f"ball is {d * 1e3:.2f} mm apart at the start")
    assert "collision.safety_distance" in failure["message"]
    # A ball 5 mm smaller (the pair 23.4 mm apart) is no reason to refuse: the run starts.
    ball["sphere"]["radius"] = 45
    data = with_obstacles(_beam({}), [ball], enabled=True)
    data["collision"]["exclude"] = [["follower.link2", "ball"]]
    code, err, out = _run(tmp_path, data, capsys, "--force")
    assert json.loads((out / "summary.json").read_text())["samples"] > 0, err
