"""The collision configs: each builds with its scene, keeps its clearance, and penetrates
without collision avoidance.

* ``ur5_pair_collision``: the follower's grasp slides into the leader's hand; the two
  wrists' clearance (arm against arm) binds.
* ``panda_pair_shelf``: two 7-joint arms carry a bar in under a shelf; the arms' clearance
  to the shelf binds and the elbows swing out in the null space.

The slow tests run each file through ``dualarm-qp run`` and read ``trajectory.csv``:
with ``collision.enabled: true`` every recorded clearance stays at or above ``d_s`` (read
from the YAML) less the documented 1 mm allowance and the binding group sits on ``d_s``
for a stretch of the run; with ``collision.enabled: false`` the same group goes below 0.
The elbows' swing is measured with the URDF oracle (:mod:`urdf_oracle`), not with the
library's kinematics.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from clearance_check import check_clearance, penetrations, recompute
from csv_check import check_valid, joint_columns, read_trajectory
from urdf_oracle import UrdfChain, homogeneous, rpy_matrix

from dualarm_qp.cli import main
from dualarm_qp.experiments import build_experiment
from dualarm_qp.experiments.config import load_config
from dualarm_qp.kinematics.robots import example_robot_urdf, example_robots_dir

pytestmark = pytest.mark.skipif(
    example_robots_dir() is None,
    reason="example-robot-data is not installed (pip install -e '.[robots]'; '.[dev]' has it)")

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
#: How far a recorded clearance may fall below d_s [m] (docs: the step's second-order term).
ALLOWANCE = 1e-3
MM = 1e-3
DEG = math.pi / 180.0


@dataclass(frozen=True)
class Case:
    """What a config's header promises."""

    obstacles: tuple[str, ...]
    pairs: dict[str, int]       # pairs per group in the scene
    bound: dict[str, int]       # CSV column: at least this many samples within 1 mm of d_s
    binding: frozenset[str]     # the nearest pairs while they are held at d_s
    deepest: str                # the pair deepest in without collision avoidance
    open_group: str             # the CSV column that goes below 0 without it


CASES = {
    # The follower's grasp slides into the leader's hand: the wrists bind.
    "ur5_pair_collision": Case(
        (),
        # 7 bodies per arm (base + 6 links); the hands' 4 links near their grasp points
        # are not paired with the bar.
        {"arm_arm": 48, "arm_object": 6, "obstacle": 0, "self": 0},
        {"clearance_arm_arm": 60}, frozenset({"leader.link5 - follower.link5"}),
        "leader.link5 - follower.link5", "clearance_arm_arm"),
    # Under the shelf: the elbows and forearms bind, and the hands at the end.
    "panda_pair_shelf": Case(
        ("shelf",),
        # 8 bodies per arm; 16 links and the bar against the shelf; links at least three
        # joints apart of each 7-joint arm.
        {"arm_arm": 63, "arm_object": 10, "obstacle": 15, "self": 30},
        {"clearance_obstacles": 100, "clearance_arm_arm": 30},
        frozenset({"follower.link4 - shelf", "leader.link5 - shelf",
                   "leader.link7 - follower.link7"}),
        "leader.link4 - shelf", "clearance_obstacles"),
}
GROUP_COLUMNS = ("clearance_arm_arm", "clearance_arm_object", "clearance_obstacles",
                 "clearance_self")


def _yaml(name: str) -> dict[str, Any]:
    return yaml.safe_load((CONFIGS / f"{name}.yaml").read_text())


def _safety(data: dict[str, Any]) -> float:
    """d_s [m] from the YAML (the files state mm)."""
    assert data["units"]["length"] == "mm"
    return float(data["collision"]["safety_distance"]) * MM


# ------------------------------------------------------------------ fast: the scenes
@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(CASES))
def test_config_builds_with_its_scene(name: str) -> None:
    case, data = CASES[name], _yaml(name)
    exp = build_experiment(load_config(CONFIGS / f"{name}.yaml"))
    scene = exp.task.scene
    assert scene is not None and scene.settings.enabled
    c = data["collision"]
    assert scene.settings.safety_distance == pytest.approx(c["safety_distance"] * MM)
    assert scene.settings.influence_distance == pytest.approx(c["influence_distance"] * MM)
    assert scene.settings.approach_speed_max == pytest.approx(c["approach_speed_max"] * MM)
    assert [b.name for b in scene.obstacles] == list(case.obstacles)
    assert "object" in scene.body_names
    counts = {g: sum(p.group == g for p in scene.pairs) for g in case.pairs}
    assert counts == case.pairs
    assert case.binding <= set(scene.pair_names) and case.deepest in scene.pair_names
    # Only the grasping hands and the pairs of bases and fixed obstacles (no joint moves
    # either) are left out; nothing overlaps at the start.
    assert all(why.startswith("the grasping hand") or why == "neither body moves"
               for _, why in scene.excluded)
    # The bar's box lies under both hands: each grasp point on its top face.
    q_l, q_f = exp.initial.q_l, exp.initial.q_f
    task = exp.task
    frames = scene.frames(task.leader.link_frames(q_l), task.follower.link_frames(q_f),
                          task.leader.fk(q_l) @ task.H1)
    bar = scene.placed(frames)[scene.body_names.index("object")]
    half = np.array(data["object"]["shape"]["box"]["size"]) * MM / 2
    for hand in (task.leader.fk(q_l), task.follower.fk(q_f)):
        local = bar.pose[:3, :3].T @ (hand[:3, 3] - bar.pose[:3, 3])
        assert local[0] == pytest.approx(-half[0], abs=1e-6)  # object x: down, into the bar
        assert np.all(np.abs(local[1:]) < half[1:])


@pytest.mark.parametrize("name", sorted(CASES))
def test_sns_refuses_the_config(name: str, tmp_path: Path,
                                capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "out"
    assert main(["run", str(CONFIGS / f"{name}.yaml"), "--solver", "sns", "--out", str(out),
                 "--quiet", "--no-plots"]) == 2
    assert "collision" in capsys.readouterr().err
    assert not out.exists() or not any(out.iterdir())


# ------------------------------------------------------------------ slow: the runs
def _run(name: str, out: Path, *, enabled: bool, solver: str | None = None
         ) -> tuple[int, dict[str, Any], dict[str, np.ndarray], dict[str, Any]]:
    """Run the config with ``collision.enabled`` set; exit code, summary, CSV, YAML."""
    data = _yaml(name)
    data["collision"]["enabled"] = enabled
    config = out.parent / f"{name}.yaml"
    config.write_text(yaml.safe_dump(data))
    argv = ["run", str(config), "--out", str(out), "--quiet", "--no-plots"]
    code = main(argv + (["--solver", solver] if solver else []))
    summary = json.loads((out / "summary.json").read_text())
    return code, summary, read_trajectory(out / "trajectory.csv"), data


def _experiment(name: str, out: Path) -> Any:
    """The experiment as the run in ``out`` ran it (from its own config.yaml)."""
    return build_experiment(load_config(out / "config.yaml"), str(CONFIGS / f"{name}.yaml"))


def _swivel(chain: UrdfChain, base: np.ndarray, q: np.ndarray) -> float:
    """Angle [rad] of the elbow (joint 4) about the shoulder-wrist line, from the plane
    through that line and the vertical."""
    frames = chain.frames(q, base)
    shoulder, elbow, wrist = (frames[k][:3, 3] for k in (1, 3, 5))
    axis = (wrist - shoulder) / np.linalg.norm(wrist - shoulder)
    out = elbow - shoulder
    out -= axis * (axis @ out)
    up = np.array([0.0, 0.0, 1.0]) - axis * axis[2]
    return math.atan2(float(np.cross(up, out) @ axis), float(up @ out))


def _end_swivels(data: dict[str, Any], traj: dict[str, np.ndarray]) -> list[float]:
    """Both arms' elbow swing [rad] on the last row, from the CSV's joints."""
    out = []
    for role, prefix in (("leader", "ql"), ("follower", "qf")):
        spec = data[role]
        model = spec["example_robot"]
        chain = UrdfChain(example_robot_urdf(model["name"]), model["root"], model["tip"])
        base = homogeneous(rpy_matrix(*(v * DEG for v in spec["base"].get("rpy", [0, 0, 0]))),
                           np.array(spec["base"]["position"], dtype=float) * MM)
        q = np.array([traj[c][-1] for c in joint_columns(traj, prefix)])
        out.append(_swivel(chain, base, q))
    return out


@pytest.mark.slow
@pytest.mark.parametrize("solver", [None, "qp:daqp"])
@pytest.mark.parametrize("name", sorted(CASES))
def test_config_keeps_its_clearance(name: str, solver: str | None, tmp_path: Path) -> None:
    case = CASES[name]
    code, summary, traj, data = _run(name, tmp_path / "out", enabled=True, solver=solver)
    assert code == 0, summary.get("failure")
    assert summary["completed"] and summary["path_completed_pct"] == pytest.approx(100.0)
    assert not check_valid(traj)
    d_s = _safety(data)
    for column in GROUP_COLUMNS:
        if column in traj:
            assert traj[column].min() >= d_s - ALLOWANCE, column
    for column, samples in case.bound.items():
        assert np.sum(traj[column] < d_s + 1e-3) >= samples, column
    bound = np.flatnonzero(np.minimum.reduce([traj[c] for c in case.bound]) < d_s + 1e-3)
    assert {traj["clearance_pair"][k] for k in bound} <= case.binding
    assert summary["realised_limits"]["clearance"]["pair"] in case.binding
    # Every pair recomputed from the CSV's joints with the tests' own kinematics and
    # distances (not the library's, not coal): the columns agree and d_s is kept.
    assert check_clearance(traj, _experiment(name, tmp_path / "out")) == []
    if name == "ur5_pair_collision":
        assert traj["grasp"][-1] > 0.12  # the grasp stops short of the leader's hand (m)
    else:
        assert all(abs(a) > 25 * DEG for a in _end_swivels(data, traj))  # elbows swing out


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(CASES))
def test_config_penetrates_without_collision_avoidance(name: str, tmp_path: Path,
                                                       capsys: pytest.CaptureFixture[str]
                                                       ) -> None:
    case = CASES[name]
    code, summary, traj, data = _run(name, tmp_path / "out", enabled=False)
    assert code == 0 and summary["completed"]  # measured only: the run is not failed
    assert traj[case.open_group].min() < 0.0
    assert traj["clearance_pair"][int(np.argmin(traj[case.open_group]))] == case.deepest
    clearance = summary["realised_limits"]["clearance"]
    assert clearance["penetration"] and not clearance["enforced"]
    assert clearance["pair"] == case.deepest
    assert any("penetrates" in w for w in summary["warnings"])
    assert "; PENETRATION" in capsys.readouterr().out  # the console's clearance line
    deepest = penetrations(recompute(traj, _experiment(name, tmp_path / "out")))
    assert any(case.deepest in line for line in deepest), deepest  # found independently
    if name == "ur5_pair_collision":
        assert traj["grasp"][-1] < 0.06  # the grasp slides on into the leader's hand (m)
    else:
        assert all(abs(a) < 10 * DEG for a in _end_swivels(data, traj))  # elbows stay up
