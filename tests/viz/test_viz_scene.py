"""The scene and the samples the page draws agree with the arms' own kinematics."""

from __future__ import annotations

import base64
import json

import numpy as np
import pinocchio as pin
import pytest

from dualarm_qp.cli import main
from dualarm_qp.errors import InvalidInputError
from dualarm_qp.experiments.animate import animate_run
from dualarm_qp.viz.frames import (
    LIMIT_NEAR,
    LIMIT_OK,
    LIMIT_OUTSIDE,
    frame_payload,
    limit_states,
    read_timeline,
)
from dualarm_qp.viz.scene import arm_node_poses, arm_parts


def _matrix(pose16):
    return np.array(pose16).reshape(4, 4).T  # column-major, as three.js reads it


def _pose(p7):
    T = np.eye(4)
    w, x, y, z = (float(v) for v in (p7[6], p7[3], p7[4], p7[5]))
    T[:3, :3] = pin.Quaternion(w, x, y, z).normalized().toRotationMatrix()
    T[:3, 3] = p7[:3]
    return T


@pytest.mark.parametrize("role", ["leader", "follower"])
def test_each_link_joins_its_two_frame_origins_in_any_configuration(beam, role):
    arm = getattr(beam.task, role)
    parts = arm_parts(arm, role)
    links = [p for p in parts["parts"] if p["shape"] == "cylinder"]
    assert len(links) >= 3
    rng = np.random.default_rng(3)
    for _ in range(3):
        q = rng.uniform(arm.q_min, arm.q_max)
        nodes = arm_node_poses(arm, q)
        origins = nodes[:, :3, 3]
        for link in links:
            T = nodes[link["node"]] @ _matrix(link["pose"])
            half = 0.5 * link["length"] * T[:3, 1]  # three.js cylinders lie along y
            ends = [T[:3, 3] - half, T[:3, 3] + half]
            for end in ends:
                assert np.min(np.linalg.norm(origins - end, axis=1)) < 1e-6  # rounded poses


def test_the_samples_are_the_arms_forward_kinematics(beam, run_dir):
    timeline = read_timeline(run_dir / "trajectory.csv")
    payload = frame_payload(beam.task, timeline)
    nodes = np.frombuffer(base64.b64decode(payload["nodes"]), dtype="<f4")
    per = 7 * (beam.task.leader.n + 2 + beam.task.follower.n + 2) + 7
    nodes = nodes.reshape(len(payload["t"]), per)
    k = len(payload["t"]) // 2
    leader = arm_node_poses(beam.task.leader, timeline.q_l[k])
    got = _pose(nodes[k, 7 * (beam.task.leader.n + 1):7 * (beam.task.leader.n + 2)])
    np.testing.assert_allclose(got, leader[-1], atol=1e-5)  # the leader's tool
    obj = _pose(nodes[k, -7:])
    np.testing.assert_allclose(obj, beam.task.leader.fk(timeline.q_l[k]) @ beam.task.H1,
                               atol=1e-5)


def test_joint_states_inside_near_and_outside(beam):
    arm = beam.task.follower
    mid = 0.5 * (arm.q_min + arm.q_max)
    near = mid.copy()
    near[0] = arm.q_max[0] - 0.01 * (arm.q_max[0] - arm.q_min[0])
    out = mid.copy()
    out[2] = arm.q_min[2] - 0.01
    assert limit_states(arm, mid).tolist() == [LIMIT_OK] * arm.n
    assert limit_states(arm, near)[0] == LIMIT_NEAR
    assert limit_states(arm, out)[2] == LIMIT_OUTSIDE


def test_joint_counts_come_from_the_header(tmp_path):
    cols = ["t", "path_t", *[f"ql{i}" for i in range(1, 8)], *[f"qf{i}" for i in range(1, 8)],
            "grasp", "grasp_leader", "status"]
    rows = [",".join(cols), ",".join(["0.1"] * (len(cols) - 1) + ["optimal"])]
    (tmp_path / "trajectory.csv").write_text("\n".join(rows) + "\n")
    tl = read_timeline(tmp_path / "trajectory.csv")
    assert tl.q_l.shape == (1, 7) and tl.q_f.shape == (1, 7)
    assert tl.status == ["optimal"] and tl.scale is None


def test_a_trajectory_without_joints_is_refused(tmp_path):
    (tmp_path / "trajectory.csv").write_text("t,path_t,grasp\n0,0,0.1\n")
    with pytest.raises(InvalidInputError, match="ql1"):
        read_timeline(tmp_path / "trajectory.csv")


def test_a_run_writes_its_config_and_animation_and_lists_them(run_dir):
    summary = json.loads((run_dir / "summary.json").read_text())
    assert {"config.yaml", "animation.html"} <= set(summary["outputs"])
    page = (run_dir / "animation.html").read_text()
    assert "connect-src 'none'" in page and "MeshCat" in page
    assert "<script src" not in page and "<link" not in page


def test_animate_rebuilds_the_page_from_the_run_folder(run_dir, tmp_path):
    out = animate_run(run_dir, tmp_path / "again.html")
    assert out.read_text() == (run_dir / "animation.html").read_text()


def test_animate_command_exit_codes(run_dir, tmp_path, capsys):
    assert main(["animate", str(run_dir), "--out", str(tmp_path / "a.html")]) == 0
    assert (tmp_path / "a.html").stat().st_size > 500_000
    assert main(["animate", str(tmp_path)]) == 2  # no summary.json: bad input
    assert "summary.json" in capsys.readouterr().err


def test_a_sliding_leader_grasp_places_the_object_by_its_grasp(tmp_path):
    """With both grasps sliding the object sits at T_l G_l(sigma_l)^-1, read per sample."""
    import numpy as np
    import pinocchio as pin

    from dualarm_qp import DualArmTask, LinearTrajectory, PlaneBar, puma560
    from dualarm_qp.viz.frames import read_timeline, sample_nodes

    lead = PlaneBar(r_min=(0, 0, -0.4), r_max=(0, 0, 0))
    task = DualArmTask(puma560(), puma560(base=np.eye(4)), np.eye(4), PlaneBar(),
                       LinearTrajectory(np.zeros(3), np.zeros(3), tf=1.0), leader_surface=lead)
    q = np.full(6, 0.3)
    for sigma_l in (-0.3, -0.1):
        obj = sample_nodes(task, q, q, 0.2, sigma_l)["object"]
        T = task.leader.fk(q) @ np.linalg.inv(lead.pose(sigma_l))
        np.testing.assert_allclose(obj[:3], T[:3, 3], atol=1e-12)
        quat = pin.Quaternion(T[:3, :3]).coeffs()
        assert min(np.abs(np.asarray(obj[3:]) - quat).max(),
                   np.abs(np.asarray(obj[3:]) + quat).max()) < 1e-12
    # The CSV's grasp_leader column reaches the timeline.
    csv = tmp_path / "trajectory.csv"
    csv.write_text("t,path_t," + ",".join(f"ql{i}" for i in range(1, 7)) + ","
                   + ",".join(f"qf{i}" for i in range(1, 7)) + ",grasp,grasp_leader\n"
                   + "0,0," + ",".join(["0.3"] * 12) + ",0.2,-0.25\n")
    tl = read_timeline(csv)
    assert tl.grasp_leader is not None and tl.grasp_leader[0] == -0.25
