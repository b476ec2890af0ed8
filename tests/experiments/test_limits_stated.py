"""A file's limits are kept, or refused, or said: never silently off.

* ``controller.acceleration_limits`` with an arm from a URDF (which states no
  acceleration limits) and no ``qdd_max`` is refused (exit 2, naming the file, the arm and
  ``<arm>.qdd_max``); a ``qdd_max`` with ``.inf`` for a joint is an explicit "none" and
  runs;
* ``dualarm-qp run`` prints which limits it keeps (per arm and grasp, torques,
  collisions), and ``summary.json`` records them (``limits_kept``);
* a shipped file whose lengths are written in metres while it says millimetres (or the
  other way round) is refused naming ``units.length``, not with a start that cannot be
  reached.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from dualarm_qp.cli import main
from dualarm_qp.kinematics.robots import example_robots_dir

pytestmark = pytest.mark.skipif(
    example_robots_dir() is None,
    reason="example-robot-data is not installed (pip install -e '.[robots]'; '.[dev]' has it)")

CONFIGS = Path(__file__).resolve().parents[2] / "configs"


def _load(name: str) -> dict[str, Any]:
    return yaml.safe_load((CONFIGS / f"{name}.yaml").read_text())


def _run(tmp_path: Path, data: dict[str, Any], capsys: pytest.CaptureFixture[str]
         ) -> tuple[int, str, str, Path]:
    tmp_path.mkdir(parents=True, exist_ok=True)
    path = tmp_path / "case.yaml"
    path.write_text(yaml.safe_dump(data))
    out = tmp_path / "out"
    code = main(["run", str(path), "--out", str(out), "--no-plots", "--quiet"])
    captured = capsys.readouterr()
    return code, captured.out, captured.err, out


@pytest.mark.parametrize("role", ["leader", "follower"])
def test_acceleration_limits_on_an_arm_without_qdd_max_are_refused(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], role: str) -> None:
    data = _load("panda_pair_accel")
    del data[role]["qdd_max"]
    code, _, err, out = _run(tmp_path, data, capsys)
    assert code == 2, err
    line, = err.strip().splitlines()
    assert str(tmp_path / "case.yaml") in line and f"key '{role}.qdd_max'" in line
    assert "acceleration_limits is on" in line and "example_robot:panda" in line
    assert "7, in deg/s^2" in line and ".inf" in line
    assert not out.exists()


def test_an_explicit_inf_leaves_a_joint_unlimited_and_says_so(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    data = _load("panda_pair_accel")
    data["follower"]["qdd_max"][1] = float("inf")
    code, stdout, err, out = _run(tmp_path, data, capsys)
    assert code == 0, err
    assert ("limits kept: leader range 7/7, speed 7/7, acceleration 7/7; follower range "
            "7/7, speed 7/7, acceleration 6/7 (none: qf2)") in stdout
    assert "    grasp range, speed, acceleration; torque off; collision off" in stdout
    kept = json.loads((out / "summary.json").read_text())["limits_kept"]
    assert kept["enforced"] is True
    assert kept["follower"] == {"joints": 7, "range": [], "speed": [], "acceleration": ["qf2"],
                                "jerk": None, "torque": None}
    assert kept["grasp"] == {"range": True, "speed": True, "acceleration": True, "jerk": None}
    assert kept["collision"] is None


def test_the_console_names_joints_without_a_range_and_settings_off(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The Kinova pair: three continuous joints per arm, no acceleration limits, a grasp
    acceleration left out; a reference solver keeps none."""
    data = _load("kinova_pair")
    data["controller"].update(duration=0.2, acceleration_limits=True)
    for role in ("leader", "follower"):
        data[role]["qdd_max"] = [100] * 6
    code, stdout, err, _ = _run(tmp_path, data, capsys)
    assert code == 0, err
    assert ("limits kept: leader range 3/6 (none: ql1, ql4, ql6), speed 6/6, acceleration "
            "6/6; follower range 3/6 (none: qf1, qf4, qf6), speed 6/6, acceleration 6/6"
            ) in stdout
    assert "    grasp range, speed, acceleration none; torque off; collision off" in stdout
    data["solver"] = {"name": "reference"}
    data["controller"]["velocity_limits"] = False
    code, stdout, err, _ = _run(tmp_path / "ref", data, capsys)
    assert "limits kept: none (this solver does not enforce limits" in stdout


def _in_metres(data: dict[str, Any]) -> dict[str, Any]:
    """``data`` (a mm file) with every length written in metres, the units left as mm."""
    for role in ("leader", "follower"):
        data[role]["base"]["position"] = [v / 1000 for v in data[role]["base"]["position"]]
    data["object"]["H1"]["position"] = [v / 1000 for v in data["object"]["H1"]["position"]]
    surface = data["object"]["surface"]
    for key in ("r_min", "r_max"):
        surface[key] = [v / 1000 for v in surface[key]]
    data["object"]["grasp_initial"] /= 1000
    data["trajectory"]["start"]["position"] = [v / 1000 for v in
                                               data["trajectory"]["start"]["position"]]
    data["trajectory"]["velocity"] = [v / 1000 for v in data["trajectory"]["velocity"]]
    data["controller"]["grasp_speed_max"] /= 1000
    return data


@pytest.mark.parametrize("slip", ["metres-in-mm", "mm-in-metres"])
def test_a_units_slip_is_named_not_blamed_on_the_start(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], slip: str) -> None:
    data = _load("ur5_pair_sliding_bar")
    assert data["units"]["length"] == "mm"
    if slip == "metres-in-mm":
        data = _in_metres(data)
        words = ("0.5 mm from the leader's base", "of the arm's reach",
                 "units.length is mm: every length of the file is read in millimetres")
    else:
        data["units"]["length"] = "m"
        words = ("500 m from the leader's base", "times the arm's reach",
                 "units.length is m: every length of the file is read in metres")
    code, _, err, out = _run(tmp_path, data, capsys)
    assert code == 2, err
    line, = err.strip().splitlines()
    assert str(tmp_path / "case.yaml") in line and "key 'units.length'" in line
    assert "the file's units may be wrong" in line and "no joints found" not in line
    assert "D(t0) H1^-1 at the path's start (trajectory.start, object.H1)" in line
    for word in words:
        assert word in line, (word, line)
    assert not out.exists()
    # Written in metres and said to be metres, the same file runs as the shipped one.
    data = _in_metres(_load("ur5_pair_sliding_bar"))
    data["units"]["length"] = "m"
    data["controller"]["duration"] = 0.2
    code, _, err, _ = _run(tmp_path / "right", data, capsys)
    assert code == 0, err


def test_the_shipped_start_is_well_within_reach() -> None:
    """The thresholds leave every shipped robot config alone (a factor 10 both ways)."""
    from dualarm_qp.experiments import build_experiment, parse_config
    from dualarm_qp.kinematics.reach import arm_reach

    for name in ("ur5_pair_sliding_bar", "kinova_pair", "ur10_panda_pair", "baxter_tray"):
        exp = build_experiment(parse_config(_load(name), name), name)
        for arm, q in ((exp.task.leader, exp.initial.q_l), (exp.task.follower, exp.initial.q_f)):
            d = float(np.linalg.norm(arm.fk(q)[:3, 3] - arm.base[:3, 3]))
            assert 0.1 < d / arm_reach(arm) < 1.0, (name, arm.name)


def test_jerk_limits_are_named_when_kept(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The FR3 pair keeps jerk limits (every joint must state one): the console and
    summary.json say so; without them the jerk is not named."""
    pytest.importorskip("franky_sim")  # the FR3's description ('.[franka]'; '.[dev]' has it)
    data = _load("fr3_pair")
    data["controller"]["duration"] = 0.05
    code, stdout, err, out = _run(tmp_path, data, capsys)
    assert code == 0, err
    assert ("limits kept: leader range 7/7, speed 7/7, acceleration 7/7, jerk 7/7; follower "
            "range 7/7, speed 7/7, acceleration 7/7, jerk 7/7") in stdout
    assert "    grasp range, speed, acceleration, jerk; torque off; collision off" in stdout
    kept = json.loads((out / "summary.json").read_text())["limits_kept"]
    assert kept["leader"]["jerk"] == [] and kept["follower"]["jerk"] == []
    assert kept["grasp"]["jerk"] is True
    data["controller"]["jerk_limits"] = False
    code, stdout, err, out = _run(tmp_path / "off", data, capsys)
    assert code == 0, err
    assert ("limits kept: leader range 7/7, speed 7/7, acceleration 7/7; follower range "
            "7/7, speed 7/7, acceleration 7/7\n    grasp range, speed, acceleration; torque "
            "off") in stdout
