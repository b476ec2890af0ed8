"""The physics verdict, recomputed from trajectory.csv of the same closed loop.

``dualarm-qp run --plant mujoco`` records the closed loop's measurements in
trajectory.csv; ``dualarm-qp physics`` on its folder runs the same closed loop (the
same controller, settings and start: MuJoCo is deterministic) and judges it. Here the
peaks the verdict reads are recomputed from the CSV alone (the object's pose against
``D(t)`` of the file's path, the measured wrenches against the plan's split of the
load, the joints' measured share of their torque limits) and judged against the
thresholds in ``summary.json``.
"""

from __future__ import annotations

import csv
import dataclasses
import json
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from dualarm_qp.cli import main
from dualarm_qp.experiments import build_experiment, load_config
from dualarm_qp.kinematics.robots import example_robots_dir
from dualarm_qp.task.hands import hand_wrenches
from dualarm_qp.task.loads import ObjectLoad

pytest.importorskip("mujoco", reason="the physics check needs MuJoCo "
                                     "(pip install -e '.[physics]'; '.[dev]' has it)")

HEAVY = Path(__file__).resolve().parents[2] / "configs" / "ur5_pair_heavy_bar.yaml"
UP = np.array([0.0, 0.0, 1.0])


def _columns(path: Path) -> dict[str, np.ndarray]:
    with path.open() as fh:
        rows = list(csv.DictReader(fh))
    return {k: np.array([float(r[k]) for r in rows]) for k in rows[0]
            if k not in ("status", "clearance_pair")}


def _deviation(c: dict[str, np.ndarray], exp) -> tuple[np.ndarray, np.ndarray]:
    """The object frame's distance [m] and turn [rad] from D(path_t), sample by sample."""
    pos, rot = [], []
    for k in range(c["t"].size):
        D = exp.task.trajectory.pose(float(c["path_t"][k]))
        q = pin.Quaternion(c["object_qw"][k], c["object_qx"][k], c["object_qy"][k],
                           c["object_qz"][k])
        p = np.array([c["object_x"][k], c["object_y"][k], c["object_z"][k]])
        pos.append(np.linalg.norm(p - D[:3, 3]))
        rot.append(np.linalg.norm(pin.log3(D[:3, :3].T @ q.toRotationMatrix())))
    return np.array(pos), np.array(rot)


def _split_error(c: dict[str, np.ndarray], exp, load: ObjectLoad) -> np.ndarray:
    """Each hand's measured lift against the plan's, relative, the larger of the two."""
    task = dataclasses.replace(exp.task, load=load)
    out = []
    for k in range(c["t"].size):
        q_l = np.array([c[f"ql{j + 1}"][k] for j in range(task.leader.n)])
        plan = hand_wrenches(task, q_l, float(c["grasp"][k])).wrenches[:, :3] @ UP
        lift = np.array([c["wrench_leader_fz"][k], c["wrench_follower_fz"][k]])
        out.append(np.max(np.abs(lift - plan) / np.abs(plan)))
    return np.array(out)


@pytest.mark.slow
@pytest.mark.skipif(example_robots_dir() is None,
                    reason="example-robot-data is not installed")
def test_the_verdict_of_the_compliant_heavy_bar_from_trajectory_csv(tmp_path):
    out = tmp_path / "run"
    assert main(["run", str(HEAVY), "--out", str(out), "--quiet", "--no-plots",
                 "--plant", "mujoco"]) == 0
    assert main(["physics", str(out)]) == 0
    p = json.loads((out / "summary.json").read_text())["physics"]
    s, loop = p["settings"], p["closed_loop"]
    c = _columns(out / "trajectory.csv")
    assert c["t"].size == loop["samples"]
    exp = build_experiment(load_config(HEAVY), str(HEAVY))
    pos, rot = _deviation(c, exp)
    assert pos.max() == pytest.approx(loop["deviation_pos_max_m"], rel=1e-6)
    assert rot.max() == pytest.approx(loop["deviation_rot_max_rad"], rel=1e-6)
    assert c["internal_force"].max() == pytest.approx(loop["internal_force_max_N"], rel=1e-9)
    load = exp.task.load
    assert load is not None
    split = _split_error(c, exp, load)
    assert split.max() == pytest.approx(loop["split_error_max"], rel=1e-6)
    # The verdict's criteria that the CSV holds, judged again: none passed.
    assert pos.max() <= s["deviation_max_m"] and rot.max() <= s["rotation_max_rad"]
    squeeze = c["internal_force"].max() - p["replay"]["internal_force_max_N"]
    assert squeeze <= s["squeeze_max_N"]
    torque = c["torque_ratio_measured"]
    assert torque.max() == pytest.approx(loop["torque_ratio_max"], rel=1e-9)
    assert torque.max() <= s["torque_ratio_max"]  # the file's allowance, 1.02
    assert split.max() < 0.10  # the compliant follower keeps the plan's split
    assert p["status"] == "ok" and loop["cause"] is None
