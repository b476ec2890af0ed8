"""configs/puma_beam_pillar.yaml: the beam task with a pillar beside the end of the path.

The file's claim, checked on the recorded motion: with collision avoidance the sliding
grasp carries the beam to the end of the path and keeps the safety distance; without it,
the sliding grasp and the fixed grasp (Zheng-Luh) both drive the follower's upper arm
into the pillar. The distance of that pair is recomputed here from the CSV's joints with
the independent DH oracle (``tests/dh_oracle.py``) and a point-to-segment distance in
the floor plane (the pillar is vertical and longer than the arms reach), sharing no code
with the library's kinematics or distances.
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

import dh_oracle
import numpy as np
import pytest
import yaml

from dualarm_qp.cli import main
from dualarm_qp.experiments import build_experiment, load_config
from dualarm_qp.experiments.figures import RunData
from dualarm_qp.geometry.shapes import Box, Capsule

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
PILLAR = CONFIGS / "puma_beam_pillar.yaml"

#: PUMA 560, Table 1, as oracle rows (a [m], alpha [rad], d [m], offset).
PUMA_ROWS = np.column_stack([np.array([0.0, 431.8, -20.32, 0.0, 0.0, 0.0]) / 1000.0,
                             np.deg2rad([-90.0, 0.0, 90.0, -90.0, 90.0, 0.0]),
                             np.array([0.0, 149.09, 0.0, 433.07, 0.0, 56.25]) / 1000.0,
                             np.zeros(6)])
UPPER_ARM_RADIUS = 0.10      # the PUMA preset's capsule of link 2 [m] (docs/kinematics.md)
PILLAR_AXIS = np.array([0.630, 1.100])  # the file's pillar [m]
PILLAR_RADIUS = 0.050
D_S, ALLOWANCE = 0.020, 0.001  # the file's safety distance; the recorded allowance [m]


def short_pillar(tmp_path: Path, duration: float) -> Path:
    d = yaml.safe_load(PILLAR.read_text())
    d["controller"]["duration"] = duration
    path = tmp_path / "pillar_short.yaml"
    path.write_text(yaml.safe_dump(d))
    return path


def test_the_pillar_file_builds_a_scene_with_the_pillar_and_the_beam():
    exp = build_experiment(load_config(PILLAR), str(PILLAR))
    scene = exp.task.scene
    assert scene is not None and exp.solver_name == "nullspace"
    s = scene.settings
    assert s.enabled and (s.safety_distance, s.influence_distance) == pytest.approx(
        (0.020, 0.100))
    leader_T = exp.task.leader.link_frames(exp.initial.q_l)
    follower_T = exp.task.follower.link_frames(exp.initial.q_f)
    T_object = exp.task.object_pose(exp.initial.q_l)
    placed = dict(zip(scene.body_names, scene.placed(scene.frames(leader_T, follower_T,
                                                                    T_object)), strict=True))
    pillar = placed["pillar"]
    assert isinstance(pillar, Capsule) and pillar.radius == pytest.approx(0.05)
    np.testing.assert_allclose([pillar.a, pillar.b], [[0.63, 1.1, -1.0], [0.63, 1.1, 1.0]],
                               atol=1e-12)
    beam = placed["object"]
    assert isinstance(beam, Box)
    np.testing.assert_allclose(beam.size, [0.04, 0.04, 0.48])
    # Along the object's z axis (world +y at D(t0)) from the leader's hand to 30 mm past
    # the follower's grasp (450 mm), 260.4 mm up: D(t0) of the file.
    hand = np.array([-0.0003, 0.690, 0.2604])
    np.testing.assert_allclose(beam.pose[:3, 2], [0, 1, 0], atol=1e-12)
    np.testing.assert_allclose(beam.pose[:3, 3], hand + np.array([0, 0.240, 0]), atol=1e-9)
    np.testing.assert_allclose(exp.task.follower.fk(exp.initial.q_f)[:3, 3],
                               hand + np.array([0, 0.450, 0]), atol=1e-6)
    pairs = set(scene.pair_names)
    assert {"follower.link2 - pillar", "object - pillar", "leader.link2 - pillar"} <= pairs
    assert not [p for p, why in scene.excluded if "overlapping" in why]
    # The path is free: at the end of D(t) (x = 499.7 mm) the beam's side face stands at
    # x = 519.7 mm, the pillar's surface at 580 mm.
    assert PILLAR_AXIS[0] - PILLAR_RADIUS - (0.4997 + 0.020) > D_S


def test_a_run_with_a_scene_prints_its_clearance_and_draws_its_figures(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["run", str(short_pillar(tmp_path, 0.31)), "--out", str(out),
                 "--quiet"]) == 0
    printed = capsys.readouterr().out
    assert "clearance    smallest 263.0 mm (follower.link1 - pillar" in printed
    s = json.loads((out / "summary.json").read_text())
    assert {"joints.png", "grasp.png", "report.html"} <= set(s["outputs"])
    data = RunData.read(out / "trajectory.csv")  # the nearest pair's name is text
    assert set(data.columns["clearance_pair"]) == {"follower.link1 - pillar"}
    np.testing.assert_allclose(np.nanmin(data.col("clearance_obstacles")),
                               s["realised_limits"]["clearance"]["min_m"])


def upper_arm_clearance(rows: list[dict[str, str]], base: np.ndarray) -> np.ndarray:
    """The follower's link-2 capsule against the pillar at each row [m], independently."""
    out = np.empty(len(rows))
    for k, row in enumerate(rows):
        q = np.array([float(row[f"qf{i}"]) for i in range(1, 7)])
        T = dh_oracle.frames(PUMA_ROWS, q, "standard", base)
        a, b = T[1][:2, 3], T[2][:2, 3]  # segment 2 joins frames 1 and 2 (floor plane)
        ab = b - a
        t = np.clip((PILLAR_AXIS - a) @ ab / (ab @ ab), 0.0, 1.0)
        out[k] = np.linalg.norm(PILLAR_AXIS - (a + t * ab)) - UPPER_ARM_RADIUS - PILLAR_RADIUS
    return out


@pytest.mark.slow
def test_the_sliding_grasp_avoids_the_pillar_and_the_others_run_into_it(tmp_path):
    """The whole file three ways (``dualarm-qp collisions``), checked from the CSVs."""
    out = tmp_path / "cmp"
    assert main(["collisions", str(PILLAR), "--out", str(out), "--quiet", "--no-plots"]) == 0
    record = json.loads((out / "collisions.json").read_text())
    assert record["claims"] == {"avoiding_completes_and_keeps_clearance": True,
                                "not_avoiding_penetrates": True,
                                "fixed_grasp_penetrates": True}
    base = build_experiment(load_config(PILLAR), str(PILLAR)).task.follower.base
    np.testing.assert_allclose(base[:3, 3], [0.300, 1.380, 0.0], atol=1e-3)  # the paper's
    nearest, upper_arm, grasp = {}, {}, {}
    for label in ("avoiding", "not_avoiding", "fixed_grasp"):
        with (out / label / "trajectory.csv").open(newline="") as fh:
            rows = list(csv.DictReader(fh))
        groups = np.array([[float(r[c]) for c in ("clearance_arm_arm", "clearance_arm_object",
                                                  "clearance_obstacles")] for r in rows])
        nearest[label] = groups.min(axis=1)
        upper_arm[label] = upper_arm_clearance(rows, base)
        grasp[label] = np.array([float(r["grasp"]) for r in rows])
        # Where the CSV names the upper arm and the pillar as the nearest pair, its
        # distance is the one recomputed here; elsewhere the pair is no nearer.
        named = np.array([r["clearance_pair"] == "follower.link2 - pillar" for r in rows])
        assert named[-1]
        np.testing.assert_allclose(groups[named, 2], upper_arm[label][named], atol=1e-9)
        assert (upper_arm[label] >= groups[:, 2] - 1e-9).all()
        assert float(rows[-1]["path_t"]) == pytest.approx(15.5)  # the whole path
    # Avoiding: every recorded distance at or above d_s less the allowance; the grasp
    # slid towards the leader to make room.
    assert nearest["avoiding"].min() >= D_S - ALLOWANCE
    assert upper_arm["avoiding"].min() >= D_S - ALLOWANCE
    assert grasp["avoiding"][-1] < 0.2
    # Not avoiding: the sliding grasp hardly slides and the upper arm enters the pillar;
    # the fixed grasp holds 450 mm and enters it deeper.
    assert upper_arm["not_avoiding"].min() < -0.005 and grasp["not_avoiding"][-1] > 0.35
    assert upper_arm["fixed_grasp"].min() < upper_arm["not_avoiding"].min()
    np.testing.assert_allclose(grasp["fixed_grasp"], 0.45)
    for label in ("not_avoiding", "fixed_grasp"):
        s = json.loads((out / label / "summary.json").read_text())
        assert s["status"] == "completed" and s["realised_limits"]["clearance"]["penetration"]
        assert any("penetrates" in w for w in s["warnings"])
