"""Shapes: validation with clear errors, placement in the world, spheres as capsules."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dualarm_qp.errors import DualArmError, InvalidInputError, NonFiniteError, ShapeError
from dualarm_qp.geometry import Box, Capsule, sphere, transform_points


def pose(rotvec, p):
    T = np.eye(4)
    T[:3, :3] = pin.exp3(np.asarray(rotvec, dtype=float))
    T[:3, 3] = p
    return T


vec3 = st.lists(st.floats(-2.0, 2.0), min_size=3, max_size=3).map(np.array)


def test_capsule_keeps_read_only_copies():
    a = np.array([0.0, 0.0, 0.0])
    cap = Capsule(a, [0.0, 0.0, 1.0], 0.1)
    a[0] = 5.0
    assert cap.a[0] == 0.0
    with pytest.raises(ValueError, match="read-only"):
        cap.b[0] = 1.0
    assert cap.length == pytest.approx(1.0)
    assert not cap.is_sphere


@pytest.mark.parametrize(("args", "error", "text"), [
    (([0, 0], [0, 0, 1], 0.1), ShapeError, "capsule endpoint a"),
    (([0, 0, 0], [0, np.nan, 1], 0.1), NonFiniteError, "capsule endpoint b"),
    (([0, 0, 0], [0, 0, 1], 0.0), InvalidInputError, "positive"),
    (([0, 0, 0], [0, 0, 1], -0.1), InvalidInputError, "positive"),
    (([0, 0, 0], [0, 0, 1], np.inf), InvalidInputError, "finite"),
    (([0, 0, 0], [0, 0, 1], "wide"), InvalidInputError, "number"),
])
def test_capsule_rejects_bad_input(args, error, text):
    with pytest.raises(error, match=text) as info:
        Capsule(*args)
    assert isinstance(info.value, DualArmError)


@pytest.mark.parametrize(("args", "error", "text"), [
    (([1.0, 1.0],), ShapeError, "box size"),
    (([1.0, 0.0, 1.0],), InvalidInputError, "positive"),
    (([1.0, np.inf, 1.0],), NonFiniteError, "box size"),
    (([1.0, 1.0, 1.0], np.diag([1.0, 1.0, -1.0, 1.0])), InvalidInputError, "rotation"),
    (([1.0, 1.0, 1.0], np.eye(3)), ShapeError, "box pose"),
])
def test_box_rejects_bad_input(args, error, text):
    with pytest.raises(error, match=text):
        Box(*args)


def test_placed_rejects_a_non_rigid_pose():
    with pytest.raises(InvalidInputError, match="T_world_frame"):
        Capsule([0, 0, 0], [1, 0, 0], 0.1).placed(2.0 * np.eye(4))
    with pytest.raises(ShapeError, match="T_world_frame"):
        Box([1, 1, 1]).placed(np.eye(3))


def test_sphere_is_a_zero_length_capsule():
    s = sphere(0.2, [1.0, 2.0, 3.0])
    assert s.is_sphere and s.length == 0.0 and s.radius == 0.2
    np.testing.assert_array_equal(s.a, [1.0, 2.0, 3.0])
    np.testing.assert_array_equal(sphere(0.1).a, np.zeros(3))


@settings(max_examples=40, deadline=None)
@given(vec3, vec3, vec3, vec3, st.floats(0.01, 1.0))
def test_placed_capsule_is_the_transformed_capsule(rotvec, p, a, b, radius):
    T = pose(rotvec, p)
    world = Capsule(a, b, radius).placed(T)
    np.testing.assert_allclose(world.a, T[:3, :3] @ a + p, atol=1e-12)
    np.testing.assert_allclose(world.b, T[:3, :3] @ b + p, atol=1e-12)
    assert world.radius == radius
    assert world.length == pytest.approx(np.linalg.norm(b - a), abs=1e-12)


@settings(max_examples=40, deadline=None)
@given(vec3, vec3, vec3, vec3)
def test_placed_box_composes_poses(rotvec, p, rotvec2, p2):
    local = pose(rotvec2, p2)
    T = pose(rotvec, p)
    box = Box([0.1, 0.2, 0.3], local)
    world = box.placed(T)
    np.testing.assert_allclose(world.pose, T @ local, atol=1e-12)
    np.testing.assert_array_equal(world.size, box.size)
    np.testing.assert_allclose(world.centre, T[:3, :3] @ p2 + p, atol=1e-12)
    np.testing.assert_array_equal(world.half_size, [0.05, 0.1, 0.15])


def test_transform_points_applies_one_pose_per_point():
    rng = np.random.default_rng(0)
    T = np.array([pose(rng.normal(size=3), rng.normal(size=3)) for _ in range(5)])
    p = rng.normal(size=(5, 3))
    expected = [Ti[:3, :3] @ pi + Ti[:3, 3] for Ti, pi in zip(T, p, strict=True)]
    np.testing.assert_allclose(transform_points(T, p), expected, atol=1e-14)
