"""What the animation draws of a collision scene: obstacles, shapes, the nearest pair.

The shapes must sit where the scene's own placement puts them, sample by sample, and the
nearest pair must be the scene's own nearest measured pair, shown only within ``d_i``.
"""

from __future__ import annotations

import base64
import dataclasses
import json
import re

import numpy as np
import pytest

from dualarm_qp.collision.scene import CollisionScene
from dualarm_qp.collision.settings import CollisionSettings
from dualarm_qp.geometry.shapes import Box, Capsule
from dualarm_qp.viz.collision import collision_parts, nearest_pair
from dualarm_qp.viz.frames import frame_payload, read_timeline, sample_nodes
from dualarm_qp.viz.scene import arm_node_poses, describe_scene


def _matrix(pose16):
    return np.array(pose16).reshape(4, 4).T  # column-major, as three.js reads it


def _page_data(page: str) -> dict:
    found = re.search(r'<script id="dualarm-data" type="application/json">(.*?)</script>',
                      page, re.S)
    assert found
    return json.loads(found.group(1))


def _frames(task, q_l, q_f):
    return task.scene.frames(task.leader.link_frames(q_l), task.follower.link_frames(q_f),
                             task.object_pose(q_l))


def _with_box_scene(task):
    """The task with a boxed object and a tilted box obstacle (the parts of every kind)."""
    T = np.eye(4)
    T[:3, :3] = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    T[:3, 3] = [0.3, 0.9, -0.4]
    scene = CollisionScene.build(
        task.leader, task.follower, settings=CollisionSettings(),
        object_shape=Box([0.05, 0.03, 0.5], np.eye(4)),
        obstacles=[("shelf", Box([0.6, 0.2, 0.02], T)),
                   ("ball", Capsule([0.1, 0.5, 0.2], [0.1, 0.5, 0.2], 0.05))])
    return dataclasses.replace(task, scene=scene)


def test_a_task_without_a_scene_draws_no_collision_parts(beam, run_dir):
    assert beam.task.scene is None
    assert describe_scene(beam.task, t_start=0.0, t_end=1.0)["collision"] is None
    payload = frame_payload(beam.task, read_timeline(run_dir / "trajectory.csv"))
    assert not {k for k in payload if k.startswith("near")}
    data = _page_data((run_dir / "animation.html").read_text())
    assert data["scene"]["collision"] is None and "near_pair" not in data["frames"]


def test_the_obstacle_is_drawn_where_the_file_puts_it(pillar):
    parts = collision_parts(pillar.task.scene)
    assert [o["name"] for o in parts["obstacles"]] == ["pillar"]
    pillar_part = parts["obstacles"][0]["part"]
    assert pillar_part["shape"] == "capsule" and pillar_part["radius"] == pytest.approx(0.05)
    ends = sorted([pillar_part["a"], pillar_part["b"]], key=lambda p: p[2])
    np.testing.assert_allclose(ends, [[0.45, 1.23, -0.6], [0.45, 1.23, 0.6]], atol=1e-9)
    # every other body is a shape on a node of its arm (or the object)
    names = {s["name"] for s in parts["shapes"]}
    assert names == {b.name for b in pillar.task.scene.bodies if b.owner != "world"}
    assert parts["pairs"] == pillar.task.scene.pair_names
    assert parts["influence_distance"] == pytest.approx(0.1)
    assert parts["safety_distance"] == pytest.approx(0.02)


def test_each_shape_hangs_on_its_node_where_the_scene_places_it(pillar):
    """Node pose times the shape's local pose is the scene's placement, in any configuration."""
    task = _with_box_scene(pillar.task)
    parts = collision_parts(task.scene)
    by_name = {o["name"]: o["part"] for o in parts["obstacles"]}
    by_name.update({s["name"]: s for s in parts["shapes"]})
    kinds = {p["shape"] if "shape" in p else p["part"]["shape"] for p in by_name.values()}
    assert kinds == {"capsule", "box"}
    rng = np.random.default_rng(5)
    for _ in range(3):
        q_l = rng.uniform(task.leader.q_min, task.leader.q_max)
        q_f = rng.uniform(task.follower.q_min, task.follower.q_max)
        nodes = {"leader": arm_node_poses(task.leader, q_l),
                 "follower": arm_node_poses(task.follower, q_f),
                 "object": task.object_pose(q_l)[None], "world": np.eye(4)[None]}
        placed = task.scene.placed(_frames(task, q_l, q_f))
        for body, shape in zip(task.scene.bodies, placed, strict=True):
            entry = by_name[body.name]
            part = entry if body.owner == "world" else entry["part"]
            T = nodes[body.owner][0 if body.owner == "world" else entry["node"]]
            if isinstance(shape, Capsule):
                for end in ("a", "b"):
                    got = T[:3, :3] @ np.array(part[end]) + T[:3, 3]
                    assert min(np.linalg.norm(got - shape.a),
                               np.linalg.norm(got - shape.b)) < 1e-6
                assert part["radius"] == pytest.approx(shape.radius)
            else:
                np.testing.assert_allclose(T @ _matrix(part["pose"]), shape.pose, atol=1e-6)
                np.testing.assert_allclose(part["size"], shape.size, atol=1e-7)


def test_the_nearest_pair_is_the_scenes_nearest_within_d_i(pillar, pillar_run_dir):
    task = pillar.task
    timeline = read_timeline(pillar_run_dir / "trajectory.csv")
    payload = frame_payload(task, timeline)
    count = len(payload["t"])
    points = np.frombuffer(base64.b64decode(payload["near_points"]), dtype="<f4")
    points = points.reshape(count, 6)
    d_i = task.scene.settings.influence_distance
    shown = 0
    for k in range(0, count, 7):
        full = task.scene.measure(_frames(task, timeline.q_l[k], timeline.q_f[k]))
        j = int(np.argmin(full.prox.distance))
        if full.prox.distance[j] < d_i:
            shown += 1
            assert payload["near_pair"][k] == int(full.pairs[j])
            assert payload["near_distance"][k] == pytest.approx(full.prox.distance[j], abs=1e-6)
            np.testing.assert_allclose(points[k], np.concatenate(
                [full.prox.point_a[j], full.prox.point_b[j]]), atol=1e-6)
        else:
            assert payload["near_pair"][k] == -1 and payload["near_distance"][k] is None
            assert np.isnan(points[k]).all()
    assert shown > 0
    # the run starts with the follower's first link 42 mm from the pillar
    assert task.scene.pair_names[payload["near_pair"][0]] == "follower.link1 - pillar"
    assert payload["near_distance"][0] == pytest.approx(0.0423, abs=5e-4)
    data = _page_data((pillar_run_dir / "animation.html").read_text())
    assert data["scene"]["collision"]["obstacles"][0]["name"] == "pillar"
    assert data["frames"]["near_pair"] == payload["near_pair"]


def test_no_pair_within_d_i_draws_no_line(pillar):
    """The pillar moved away: the same start has no pair within d_i, so no line."""
    task = pillar.task
    far = CollisionScene.build(task.leader, task.follower, settings=task.scene.settings,
                               obstacles=[("pillar", Capsule([0.45, 1.8, -0.6],
                                                             [0.45, 1.8, 0.6], 0.05))])
    moved = dataclasses.replace(task, scene=far)
    q_l, q_f = pillar.initial.q_l, pillar.initial.q_f
    assert nearest_pair(moved.scene, _frames(moved, q_l, q_f)) is None
    assert sample_nodes(moved, q_l, q_f, 0.2)["nearest"] is None
    near = nearest_pair(task.scene, _frames(task, q_l, q_f))
    assert near is not None and near.name == "follower.link1 - pillar"
    assert 0.0 < near.distance < task.scene.settings.influence_distance
    assert np.linalg.norm(near.point_b - near.point_a) == pytest.approx(near.distance)
