"""The collision scene: its bodies, pairs and exclusions, and its measure."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from dualarm_qp.collision import CollisionScene, CollisionSettings
from dualarm_qp.collision.scene import ObstacleOverlapError
from dualarm_qp.errors import InvalidInputError
from dualarm_qp.geometry import Box, Capsule, capsule_proximities, proximity, sphere
from dualarm_qp.kinematics import puma560
from dualarm_qp.poses import pose


def _pumas():
    leader = puma560()
    follower = puma560().with_base(pose([0.3, 1.38, 0.0]))
    return leader, follower


def _scene(**kw):
    leader, follower = _pumas()
    kw.setdefault("settings", CollisionSettings())
    return CollisionScene.build(leader, follower, **kw), leader, follower


def test_pairs_have_their_groups_and_names():
    bar = Box([0.04, 0.04, 0.7], pose([0, 0, 0.35]))
    pillar = Capsule([0.45, 1.23, -0.6], [0.45, 1.23, 0.6], 0.05)
    scene, _, _ = _scene(object_shape=bar, obstacles=[("pillar", pillar)])
    # 6 capsules per PUMA (the column below the shoulder has none): 36 arm-arm pairs,
    # 12 link-object pairs, 13 obstacle pairs (12 links and the object); no self pairs
    # for six joints.
    groups = [p.group for p in scene.pairs]
    assert groups.count("arm_arm") == 36
    assert groups.count("arm_object") == 12
    assert groups.count("obstacle") == 13
    assert "self" not in groups
    assert "leader.link3 - follower.link4" in scene.pair_names
    assert "object - pillar" in scene.pair_names
    assert scene.summary()["pairs"] == scene.pair_names


def test_exclusions_by_name_grasp_clearance_and_start_overlap():
    bar = Box([0.04, 0.04, 0.7], pose([0, 0, 0.35]))
    leader = puma560()
    follower = puma560().with_base(pose([0.2, 0.0, 0.0]))  # shoulders 0.2 m apart: overlap
    q_l = np.zeros(6)
    q_f = np.zeros(6)
    T_object = leader.fk(q_l)
    scene = CollisionScene.build(
        leader, follower, settings=CollisionSettings(grasp_clearance=0.15),
        object_shape=bar, exclude=[("leader.link6", "follower.link6")],
        start=(q_l, q_f, T_object))
    why = dict(scene.excluded)
    assert why["leader.link6 - follower.link6"] == "excluded in the set-up"
    assert "the grasping hand" in why["leader.link6 - object"]
    overlapping = [p for p, reason in why.items() if reason.startswith("overlapping")]
    assert "leader.link1 - follower.link1" in overlapping
    assert all(p not in scene.pair_names for p in why)
    placed = scene.placed(scene.frames(leader.link_frames(q_l), follower.link_frames(q_f),
                                       T_object))
    bodies = scene.body_names
    for name in overlapping:
        a, b = name.split(" - ")
        assert proximity(placed[bodies.index(a)], placed[bodies.index(b)]).distance < 0


def test_an_obstacle_overlapping_the_start_is_an_error():
    leader, follower = _pumas()
    q = np.zeros(6)
    T_object = leader.fk(q)
    lamp = sphere(0.05, T_object[:3, 3] + np.array([0.0, 0.0, 0.3]))
    bar = Box([0.04, 0.04, 0.7], pose([0, 0, 0.35]))
    with pytest.raises(ObstacleOverlapError, match="'lamp' overlaps") as err:
        CollisionScene.build(leader, follower, settings=CollisionSettings(),
                             object_shape=bar, obstacles=[("lamp", lamp)],
                             start=(q, q, T_object))
    assert err.value.obstacle == "lamp"


def test_pairs_of_bodies_no_joint_moves_are_left_out():
    from dualarm_qp.kinematics import example_robot_arm
    from dualarm_qp.kinematics.robots import example_robots_dir

    if example_robots_dir() is None:
        pytest.skip("example-robot-data is not installed")
    ur5 = example_robot_arm("ur5", "base_link", "tool0")
    other = ur5.with_base(pose([1.0, 0.0, 0.0]))
    post = Capsule([0.5, 0.0, -1.0], [0.5, 0.0, 1.0], 0.05)
    scene = CollisionScene.build(ur5, other, settings=CollisionSettings(),
                                 obstacles=[("post", post)])
    why = dict(scene.excluded)
    for pair in ("leader.base - follower.base", "leader.base - post", "follower.base - post"):
        assert why[pair] == "neither body moves"
        assert pair not in scene.pair_names
    assert "leader.link1 - post" in scene.pair_names


def test_a_bad_exclude_name_lists_the_bodies():
    with pytest.raises(InvalidInputError, match=r"no body of the scene.*leader\.link1"):
        _scene(exclude=[("leader.link9", "object")])


def test_two_obstacles_of_one_name_are_refused():
    ball = sphere(0.1, [1.0, 1.0, 1.0])
    with pytest.raises(InvalidInputError, match="used twice"):
        _scene(obstacles=[("ball", ball), ("ball", ball)])


@pytest.mark.slow
def test_seven_joint_arms_get_self_pairs_three_joints_apart():
    from dualarm_qp.kinematics import example_robot_arm
    from dualarm_qp.kinematics.robots import example_robots_dir

    if example_robots_dir() is None:
        pytest.skip("example-robot-data is not installed")

    panda = example_robot_arm("panda", "panda_link0", "panda_link8")
    other = panda.with_base(pose([0.0, 1.0, 0.0]))
    scene = CollisionScene.build(panda, other, settings=CollisionSettings())
    selfs = [p for p in scene.pairs if p.group == "self"]
    assert selfs
    for p in selfs:
        a, b = scene.bodies[p.a], scene.bodies[p.b]
        assert a.owner == b.owner and abs(a.link - b.link) >= 3


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(q=st.lists(st.floats(-3.0, 3.0), min_size=12, max_size=12),
       within=st.floats(0.01, 0.6))
def test_measure_within_keeps_every_pair_closer_than_the_bound(q, within):
    bar = Box([0.04, 0.04, 0.7], pose([0, 0, 0.35]))
    shelf = Box([0.8, 0.3, 0.02], pose([0.2, 1.0, 0.5], rpy=[0.1, 0.2, 0.3]))
    scene, leader, follower = _scene(object_shape=bar, obstacles=[("shelf", shelf)])
    q_l, q_f = np.array(q[:6]), np.array(q[6:])
    frames = scene.frames(leader.link_frames(q_l), follower.link_frames(q_f), leader.fk(q_l))
    full = scene.measure(frames)
    part = scene.measure(frames, within=within)
    assert np.array_equal(full.pairs, np.arange(len(scene.pairs)))
    # Every pair closer than the bound is measured, with the same numbers.
    close = np.flatnonzero(full.prox.distance < within)
    assert set(close.tolist()) <= set(part.pairs.tolist())
    where = {int(p): i for i, p in enumerate(part.pairs)}
    for j in close.tolist():
        assert part.prox.distance[where[j]] == pytest.approx(full.prox.distance[j], abs=1e-12)
    # And the full measure agrees with one-pair distances of the placed shapes.
    placed = scene.placed(frames)
    for j, pair in enumerate(scene.pairs):
        one = proximity(placed[pair.a], placed[pair.b])
        assert full.prox.distance[j] == pytest.approx(one.distance, abs=1e-9)


def test_a_box_is_measured_by_coal_not_by_its_bounding_capsule():
    leader, follower = _pumas()
    shelf = Box([0.8, 0.3, 0.02], pose([0.2, 1.0, 0.5]))
    scene = CollisionScene.build(leader, follower, settings=CollisionSettings(),
                                 obstacles=[("shelf", shelf)])
    frames = scene.frames(leader.link_frames(np.zeros(6)), follower.link_frames(np.zeros(6)),
                          np.eye(4))
    m = scene.measure(frames)
    placed = scene.placed(frames)
    boxed = [j for j, pair in enumerate(scene.pairs) if isinstance(placed[pair.b], Box)]
    assert len(boxed) == 12
    for j in boxed:
        pair = scene.pairs[j]
        a, b = placed[pair.a], placed[pair.b]
        exact = proximity(a, b)
        assert m.prox.distance[j] == pytest.approx(exact.distance, abs=1e-9)
        assert np.allclose(m.prox.point_b[j] - m.prox.point_a[j],
                           m.prox.distance[j] * m.prox.normal[j], atol=1e-9)


def test_capsule_pairs_match_the_closed_form():
    scene, leader, follower = _scene()
    rng = np.random.default_rng(3)
    q_l, q_f = rng.uniform(-2, 2, 6), rng.uniform(-2, 2, 6)
    frames = scene.frames(leader.link_frames(q_l), follower.link_frames(q_f), np.eye(4))
    placed = scene.placed(frames)
    m = scene.measure(frames)
    a = [placed[p.a] for p in scene.pairs]
    b = [placed[p.b] for p in scene.pairs]
    ref = capsule_proximities(np.array([c.a for c in a]), np.array([c.b for c in a]),
                              [c.radius for c in a], np.array([c.a for c in b]),
                              np.array([c.b for c in b]), [c.radius for c in b])
    assert np.allclose(m.prox.distance, ref.distance, atol=1e-12)
