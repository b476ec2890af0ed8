"""Experiment files that take an arm from a URDF or from example-robot-data."""

from __future__ import annotations

import copy
import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from dualarm_qp.cli import main
from dualarm_qp.errors import ConfigError
from dualarm_qp.experiments.config import parse_config
from dualarm_qp.experiments.setup import build_experiment
from dualarm_qp.kinematics.robots import example_robot_urdf, example_robots_dir

PAPER = Path(__file__).resolve().parents[2] / "configs" / "puma_beam_sliding_s7_100.yaml"
BASE: dict[str, Any] = yaml.safe_load(PAPER.read_text())

needs_robots = pytest.mark.skipif(
    example_robots_dir() is None,
    reason="example-robot-data is not installed (pip install -e '.[robots]'; '.[dev]' has it)")

#: UR5 joints [deg] away from its singularities.
UR5_Q0 = [0, -60, 90, -120, -90, 30]

TWO_LINK = """<?xml version="1.0"?>
<robot name="two_link">
  <link name="world"/><link name="l1"/><link name="l2"/>
  <joint name="a" type="revolute"><parent link="world"/><child link="l1"/>
    <axis xyz="0 0 1"/><limit lower="-1" upper="1" velocity="1" effort="1"/></joint>
  <joint name="b" type="revolute"><parent link="l1"/><child link="l2"/>
    <origin xyz="0.5 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" velocity="1" effort="1"/></joint>
</robot>
"""


def config(follower: dict[str, Any], **leader: Any) -> dict[str, Any]:
    d = copy.deepcopy(BASE)
    d["follower"] = follower
    d["controller"]["duration"] = 0.31  # 10 samples
    d["object"]["grasp_initial"] = 200  # inside the bar: the UR5 stays well conditioned
    if leader:
        d["leader"] = {**d["leader"], **leader}
    return d


def ur5(model: dict[str, Any] | None = None, **extra: Any) -> dict[str, Any]:
    return {**(model or {"example_robot": {"name": "ur5", "root": "base_link",
                                           "tip": "tool0"}}),
            "base": "auto", "initial": {"joints": UR5_Q0}, **extra}


def build(d: dict[str, Any], path: Path) -> Any:
    path.write_text(yaml.safe_dump(d))
    return build_experiment(parse_config(yaml.safe_load(path.read_text()), str(path)),
                            str(path))


def config_error(d: dict[str, Any], path: Path) -> ConfigError:
    with pytest.raises(ConfigError) as err:
        build(d, path)
    return err.value


@needs_robots
def test_example_robot_follower_builds_with_urdf_limits(tmp_path: Path) -> None:
    exp = build(config(ur5()), tmp_path / "ur5.yaml")
    follower = exp.task.follower
    assert follower.n == 6 and follower.joint_names[0] == "shoulder_pan_joint"
    np.testing.assert_allclose(follower.qd_max, [3.15, 3.15, 3.15, 3.2, 3.2, 3.2])
    np.testing.assert_allclose(follower.q_max[2], np.pi, rtol=1e-11)
    # The config's limits (degrees here) override the URDF's.
    exp = build(config(ur5(qd_max=[90] * 6, q_min=[-200] * 6)), tmp_path / "ur5b.yaml")
    np.testing.assert_allclose(exp.task.follower.qd_max, np.full(6, np.pi / 2))
    np.testing.assert_allclose(exp.task.follower.q_min, np.full(6, np.radians(-200)))
    np.testing.assert_allclose(exp.task.follower.q_max[2], np.pi, rtol=1e-11)


@needs_robots
def test_urdf_file_is_relative_to_the_config_and_runs(tmp_path: Path) -> None:
    (tmp_path / "robots").mkdir()
    shutil.copy(example_robot_urdf("ur5"), tmp_path / "robots" / "ur5.urdf")
    d = config(ur5({"urdf": {"file": "robots/ur5.urdf", "root": "base_link",
                             "tip": "tool0"}}))
    path = tmp_path / "run.yaml"
    exp = build(d, path)
    assert exp.task.follower.n == 6
    code = main(["run", str(path), "--out", str(tmp_path / "out"), "--quiet", "--no-plots"])
    assert code == 0


@pytest.mark.parametrize(
    ("follower", "key", "words"),
    [
        (ur5({"urdf": {"file": "missing.urdf", "root": "world", "tip": "l2"}}),
         "follower.urdf.file", "not found"),
        (ur5({"urdf": {"file": "two_link.urdf", "root": "base", "tip": "l2"}}),
         "follower.urdf.root", "'base' not found"),
        (ur5({"urdf": {"file": "two_link.urdf", "root": "world", "tip": "hand"}}),
         "follower.urdf.tip", "'hand' not found"),
        (ur5({"urdf": {"file": "two_link.urdf", "root": "world", "tip": "l2"}}),
         "follower.urdf", "at least 5"),
        (ur5({"urdf": {"file": "two_link.urdf", "root": "world"}}),
         "follower.urdf.tip", "required"),
        (ur5({"urdf": {"file": "two_link.urdf", "root": "world", "tip": "l2"},
              "preset": "puma560"}), "follower", "exactly one"),
        (ur5({"urdf": {"file": "two_link.urdf", "root": "world", "tip": "l2",
                       "joints": 3}}), "follower.urdf.joints", "unknown key"),
    ],
)
def test_bad_urdf_keys(tmp_path: Path, follower: dict[str, Any], key: str, words: str) -> None:
    (tmp_path / "two_link.urdf").write_text(TWO_LINK)
    err = config_error(config(follower), tmp_path / "bad.yaml")
    assert err.key == key, str(err)
    assert words in str(err)


@needs_robots
def test_bad_example_robot_keys(tmp_path: Path) -> None:
    err = config_error(config(ur5({"example_robot": {"name": "nao", "root": "a", "tip": "b"}})),
                       tmp_path / "a.yaml")
    assert err.key == "follower.example_robot.name" and "ur5" in err.valid
    err = config_error(config(ur5({"example_robot": {"name": "baxter", "root": "base",
                                                     "tip": "left_hand"}})),
                       tmp_path / "b.yaml")
    assert err.key == "follower.example_robot.tip" and "left_gripper" in str(err)
    leader = {"example_robot": {"name": "ur5", "root": "base_link", "tip": "tool0"},
              "preset": None}
    err = config_error(config(ur5(), **leader), tmp_path / "c.yaml")
    assert err.key == "leader.initial.ik_branch" and "puma560" in str(err)


def test_bad_urdf_file_exits_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(config(ur5({"urdf": {"file": "nope.urdf", "root": "a",
                                                         "tip": "b"}}))))
    code = main(["run", str(path), "--out", str(tmp_path / "out"), "--quiet", "--no-plots"])
    err = capsys.readouterr().err
    assert code == 2, err
    assert "follower.urdf.file" in err and str(path) in err
    assert not (tmp_path / "out").exists()
