"""``dualarm-qp bag``: a run folder as a rosbag2 (MCAP), read back with rosbags' reader."""

from __future__ import annotations

import csv
import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_typestore

from dualarm_qp.bag import write as bag_write
from dualarm_qp.bag.write import write_bag
from dualarm_qp.cli import main
from dualarm_qp.experiments.config import load_config
from dualarm_qp.experiments.run import run_experiment
from dualarm_qp.experiments.setup import build_experiment

ROOT = Path(__file__).resolve().parents[2]
FR3 = ROOT / "configs" / "fr3_pair.yaml"
STORE = get_typestore(Stores.ROS2_JAZZY)


def read_csv(path: Path) -> list[dict[str, str]]:
    with path.open(newline="") as fh:
        return list(csv.DictReader(fh))


def read_bag(path: Path) -> dict[str, list[tuple[int, object]]]:
    out: dict[str, list[tuple[int, object]]] = {}
    with AnyReader([path], default_typestore=STORE) as reader:
        for conn, stamp, raw in reader.messages():
            out.setdefault(conn.topic, []).append((stamp, reader.deserialize(raw, conn.msgtype)))
    return out


def assert_bag_matches_run(bag: Path, run: Path, leader_names=None, follower_names=None):
    """Every message against trajectory.csv, row for row, and the poses recomputed."""
    exp = build_experiment(load_config(run / "config.yaml"), str(run / "config.yaml"))
    task = exp.task
    rows = read_csv(run / "trajectory.csv")
    msgs = read_bag(bag)
    assert sorted(msgs) == ["/diagnostics", "/dualarm/summary", "/joint_states", "/tf"]
    for topic in ("/joint_states", "/tf", "/diagnostics"):
        assert len(msgs[topic]) == len(rows), topic
    n_l, n_f = task.leader.n, task.follower.n
    names = (list(leader_names or [f"leader_joint{j + 1}" for j in range(n_l)])
             + list(follower_names or [f"follower_joint{j + 1}" for j in range(n_f)])
             + ["follower_grasp"])
    levels = {"optimal": 0, "feasible": 0, "recovering": 1, "scaled": 1, "relaxed": 1,
              "escaping": 1, "stopping": 1, "violation": 2, "error": 2, "infeasible": 2}
    for k, row in enumerate(rows):
        stamp = round(float(row["t"]) * 1e9)
        # joints with the grasp, and the commanded rates as velocities
        t_js, js = msgs["/joint_states"][k]
        assert t_js == stamp
        assert js.header.stamp.sec * 10**9 + js.header.stamp.nanosec == stamp
        assert js.name == names
        q = [float(row[f"ql{j + 1}"]) for j in range(n_l)] + [
            float(row[f"qf{j + 1}"]) for j in range(n_f)] + [float(row["grasp"])]
        assert js.position.tolist() == q  # exactly: the CSV holds repr(float)
        v = [float(row[f"ql_dot{j + 1}"]) for j in range(n_l)] + [
            float(row[f"qf_dot{j + 1}"]) for j in range(n_f)] + [float(row["m"])]
        np.testing.assert_array_equal(js.velocity, v)
        # the object carried by the leader's joints, D(path_t), the grasp point
        t_tf, tf = msgs["/tf"][k]
        assert t_tf == stamp
        poses = {(tr.header.frame_id, tr.child_frame_id): tr.transform for tr in tf.transforms}
        q_l = np.array(q[:n_l])
        want = {("world", "object"): task.leader.fk(q_l) @ task.H1,
                ("world", "object_target"): task.trajectory.pose(float(row["path_t"])),
                ("object", "follower_grasp"): task.surface.pose(float(row["grasp"]))}
        assert set(poses) == set(want)
        for key, T in want.items():
            tr = poses[key]
            p = [tr.translation.x, tr.translation.y, tr.translation.z]
            np.testing.assert_allclose(p, T[:3, 3], atol=1e-12)
            r = tr.rotation
            R = pin.Quaternion(r.w, r.x, r.y, r.z).toRotationMatrix()
            np.testing.assert_allclose(R, T[:3, :3], atol=1e-12)
            assert math.isclose(r.x**2 + r.y**2 + r.z**2 + r.w**2, 1.0, rel_tol=1e-12)
        # the step's status
        t_d, diag = msgs["/diagnostics"][k]
        assert t_d == stamp
        (status,) = diag.status
        assert status.message == row["status"]
        assert status.level == levels[row["status"]]
        values = {kv.key: float(kv.value) for kv in status.values}
        for key in ("path_t", "scale", "grasp", "closure_pos_err", "leader_pos_err"):
            assert values[key] == float(row[key]) or (math.isnan(values[key])
                                                     and row[key] == "nan"), key
    ((t_s, summary),) = msgs["/dualarm/summary"]
    assert t_s == round(float(rows[-1]["t"]) * 1e9)
    assert json.loads(summary.data) == json.loads((run / "summary.json").read_text())


def test_the_bag_reads_back_message_for_message(run_dir, capsys) -> None:
    assert main(["bag", str(run_dir)]) == 0
    assert "/joint_states" in capsys.readouterr().out
    assert (run_dir / "bag" / "metadata.yaml").is_file()
    assert (run_dir / "bag" / "bag.mcap").is_file()
    assert_bag_matches_run(run_dir / "bag", run_dir)


def test_an_existing_bag_is_kept_unless_forced(run_dir, tmp_path, capsys) -> None:
    out = tmp_path / "b"
    assert main(["bag", str(run_dir), "--out", str(out)]) == 0
    before = (out / "b.mcap").read_bytes()
    assert main(["bag", str(run_dir), "--out", str(out)]) == 2
    assert "--force" in capsys.readouterr().err
    assert main(["bag", str(run_dir), "--out", str(out), "--force"]) == 0
    assert (out / "b.mcap").read_bytes() == before  # the same run, the same bag
    other = tmp_path / "not_a_bag"
    other.mkdir()
    (other / "keep.txt").write_text("mine")
    assert main(["bag", str(run_dir), "--out", str(other), "--force"]) == 2
    assert (other / "keep.txt").read_text() == "mine"


def test_an_interrupted_write_leaves_no_bag_and_keeps_the_old(run_dir, tmp_path,
                                                              monkeypatch) -> None:
    out = tmp_path / "bag"
    write_bag(run_dir, out)
    before = sorted(p.name for p in out.iterdir())
    real = bag_write.RunStream.stream

    def cut(self):
        for i, msg in enumerate(real(self)):
            if i == 10:
                raise KeyboardInterrupt("SIGINT")
            yield msg

    monkeypatch.setattr(bag_write.RunStream, "stream", cut)
    with pytest.raises(KeyboardInterrupt):
        write_bag(run_dir, out, force=True)
    assert sorted(p.name for p in out.iterdir()) == before
    assert_bag_matches_run(out, run_dir)  # the old bag, whole
    fresh = tmp_path / "fresh"
    with pytest.raises(KeyboardInterrupt):
        write_bag(run_dir, fresh)
    assert not fresh.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bag"]  # no temporary folder left


def test_the_files_joint_names_name_the_joints(tmp_path) -> None:
    """fr3_pair names each arm's joints in its cell: section: the bag uses them."""
    exp = build_experiment(load_config(FR3), str(FR3))
    exp = dataclasses.replace(exp, duration=0.05)
    run_experiment(exp, tmp_path, progress=False, plots=False)
    path, counts = write_bag(tmp_path)
    cell = load_config(FR3).cell
    assert counts["/joint_states"] == 6
    assert_bag_matches_run(path, tmp_path, cell.leader.joints, cell.follower.joints)


@pytest.mark.parametrize("what", ["not_a_folder", "no_summary", "no_csv"])
def test_bad_run_folders_exit_2(run_dir, tmp_path, capsys, what) -> None:
    target = tmp_path / "run"
    if what != "not_a_folder":
        target.mkdir()
        (target / "config.yaml").write_text((run_dir / "config.yaml").read_text())
        if what == "no_csv":
            (target / "summary.json").write_text((run_dir / "summary.json").read_text())
    assert main(["bag", str(target)]) == 2
    err = capsys.readouterr().err
    assert {"not_a_folder": "not a folder", "no_summary": "summary.json",
            "no_csv": "trajectory.csv"}[what] in err
    assert not (target / "bag").exists()


@pytest.mark.slow
def test_the_reproductions_runs_read_back(tmp_path) -> None:
    assert main(["reproduce", "--out", str(tmp_path), "--quiet"]) == 0
    cases = sorted(p for p in tmp_path.iterdir() if p.is_dir() and p.name.startswith("case_"))
    assert len(cases) >= 3
    for case in cases:
        assert main(["bag", str(case)]) == 0
        assert_bag_matches_run(case / "bag", case)
