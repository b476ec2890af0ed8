"""configs/puma_beam_pillar.yaml: the beam task with a pillar beside the end of the path.

Its scene, and a short run from the command line. The whole file, run with and without
collision avoidance and with the fixed grasp, is checked from its recorded motion by the
slow test ``tests/executed/test_pillar_config.py``.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import yaml

from dualarm_qp.cli import main
from dualarm_qp.experiments import build_experiment, load_config
from dualarm_qp.experiments.figures import RunData
from dualarm_qp.geometry.shapes import Box, Capsule

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
PILLAR = CONFIGS / "puma_beam_pillar.yaml"

PILLAR_AXIS = np.array([0.630, 1.100])  # the file's pillar [m]
PILLAR_RADIUS = 0.050
D_S = 0.020  # the file's safety distance [m]


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


def test_the_pillar_file_runs_from_the_command_line(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["run", str(short_pillar(tmp_path, 0.31)), "--out", str(out), "--quiet",
                 "--no-plots"]) == 0
    assert "clearance    smallest 263.0 mm (follower.link1 - pillar" in capsys.readouterr().out
    s = json.loads((out / "summary.json").read_text())
    assert s["collision"]["enabled"] and "follower.link2 - pillar" in s["collision"]["pairs"]
    data = RunData.read(out / "trajectory.csv")
    assert set(data.columns["clearance_pair"]) == {"follower.link1 - pillar"}
    np.testing.assert_allclose(np.nanmin(data.col("clearance_obstacles")),
                               s["realised_limits"]["clearance"]["min_m"])
