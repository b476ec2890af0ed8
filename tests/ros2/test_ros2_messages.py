"""The node's own messages built with ROS 2's message classes, in the ROS environment.

The loopback tests hear the node's grasp joint and diagnostics through the stand-in;
its ``/tf`` they cannot (the community wheels have no ``tf2_msgs``). Here the node's
transforms of a short run of ``configs/fr3_pair.yaml`` are built with the real
``geometry_msgs/TransformStamped`` (the ``TFMessage`` taken as the list it holds) and
compared with the poses computed from the task: the object carried by the leader's
joints, ``D(path_t)`` and the grasp point.
"""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[2]

SCRIPT = r"""
import dataclasses, json, sys
import numpy as np
import pinocchio as pin
from dualarm_qp.bag.stream import Sample, StreamNames
from dualarm_qp.cell.ros2 import ros2_cell
from dualarm_qp.cell.ros2_node import Ros2Node
from dualarm_qp.experiments.config import load_config
from dualarm_qp.experiments.run import run_experiment
from dualarm_qp.experiments.setup import build_experiment

path = sys.argv[1]
cfg = load_config(path)
exp = dataclasses.replace(build_experiment(cfg, path), duration=0.05)
trace = run_experiment(exp, None, progress=False, plots=False).result.trace
cell = ros2_cell(cfg, exp, path, dry_run=True)
cell.node = Ros2Node("tf_check", use_sim_time=False)
cell.node.types = dataclasses.replace(cell.node.types, tf=lambda transforms: transforms)
task, out = exp.task, []
for k in range(len(trace.t)):
    s = Sample.from_trace(trace, k)
    stamp = cell.node.types.Time(sec=7, nanosec=k)
    want = {("world", "object"): task.leader.fk(s.q_l) @ task.H1,
            ("world", "object_target"): task.trajectory.pose(s.path_t),
            ("object", "follower_grasp"): task.surface.pose(s.grasp)}
    got = cell._tf(s, stamp)
    row = {"frames": [], "stamps": [], "err": 0.0}
    for msg in got:
        key = (msg.header.frame_id, msg.child_frame_id)
        row["frames"].append(list(key))
        row["stamps"].append([msg.header.stamp.sec, msg.header.stamp.nanosec])
        tr = msg.transform
        r = tr.rotation
        R = pin.Quaternion(r.w, r.x, r.y, r.z).toRotationMatrix()
        p = np.array([tr.translation.x, tr.translation.y, tr.translation.z])
        row["err"] = max(row["err"], float(np.max(np.abs(p - want[key][:3, 3]))),
                         float(np.max(np.abs(R - want[key][:3, :3]))),
                         abs(r.x**2 + r.y**2 + r.z**2 + r.w**2 - 1.0))
    out.append(row)
cell.close()
print(json.dumps(out))
"""


def test_the_nodes_transforms_are_the_tasks_poses(ros_env) -> None:
    done = subprocess.run([str(ros_env.python), "-c", SCRIPT,
                           str(ROOT / "configs" / "fr3_pair.yaml")], env=ros_env.env,
                          cwd=ROOT, capture_output=True, text=True, timeout=300, check=False)
    assert done.returncode == 0, done.stderr
    rows = json.loads(done.stdout.strip().splitlines()[-1])
    assert len(rows) >= 5
    for k, row in enumerate(rows):
        assert row["frames"] == [["world", "object"], ["world", "object_target"],
                                 ["object", "follower_grasp"]]
        assert row["stamps"] == [[7, k]] * 3
        assert row["err"] < 1e-12, (k, row["err"])
