"""Pairs with a box (through coal): coal's conventions, and independent checks by
clamping, by a 1-D minimisation along the capsule's axis, by bounded least squares and
(for overlapping shapes) by support functions."""

from __future__ import annotations

import coal
import numpy as np
import pinocchio as pin
import pytest
from geom_oracles import (
    box_box_distance,
    box_local,
    box_support,
    capsule_support,
    point_box_distance,
    point_segment_distance,
    segment_box_distance,
    separating_axes,
    support_signed_distance,
)
from hypothesis import assume, example, given, settings
from hypothesis import strategies as st
from scipy.optimize import minimize_scalar

from dualarm_qp.geometry import Box, Capsule, proximity, sphere

coord = st.floats(-1.0, 1.0)
vec3 = st.tuples(coord, coord, coord).map(np.array)
sizes = st.tuples(*[st.floats(0.05, 1.0)] * 3).map(np.array)


def pose(rotvec, p):
    T = np.eye(4)
    T[:3, :3] = pin.exp3(np.asarray(rotvec, dtype=float))
    T[:3, 3] = p
    return T


boxes = st.builds(lambda size, rotvec, p: Box(size, pose(rotvec, 0.3 * p)), sizes, vec3, vec3)


def check_conventions(prox):
    assert np.linalg.norm(prox.normal) == pytest.approx(1.0, abs=1e-12)
    np.testing.assert_allclose(prox.point_b - prox.point_a, prox.distance * prox.normal,
                               atol=1e-9)


# ------------------------------------------------------------------ sphere vs box: clamping
@settings(max_examples=150, deadline=None)
@given(boxes, vec3, st.floats(0.01, 0.5))
# Centred between two faces: local x is 1e-17, not 0.
@example(Box(np.array([0.25, 1.0, 1.0]), pose([0.0, 0.25, 0.25], [0.0, 0.075, 0.075])),
         np.array([0.0, 0.25, 0.25]), 0.5)
@pytest.mark.slow
def test_sphere_box_matches_clamping(box, centre, radius):
    centre = 1.5 * centre
    local = box_local(centre, box)
    half = box.half_size
    inside = bool((np.abs(local) < half).all())
    if inside:
        depths = half - np.abs(local)
        axis = int(np.argmin(depths))
        assume(np.sort(depths)[1] - depths[axis] > 1e-6)  # one nearest face
        expected = -depths[axis] - radius
        outward = np.zeros(3)
        outward[axis] = 1.0 if local[axis] >= 0.0 else -1.0
        box_normal = box.pose[:3, :3] @ outward  # from the box out through that face
        if abs(local[axis]) < 1e-9:  # centred between two faces (to roundoff): either one
            box_normal *= -np.sign(box_normal @ proximity(sphere(radius, centre), box).normal)
    else:
        gap = local - np.clip(local, -half, half)
        assume(np.linalg.norm(gap) > 1e-9)
        expected = np.linalg.norm(gap) - radius
        box_normal = box.pose[:3, :3] @ gap / np.linalg.norm(gap)
    ball = sphere(radius, centre)
    p = proximity(ball, box)  # normal from the sphere to the box
    assert p.distance == pytest.approx(expected, abs=1e-9)
    np.testing.assert_allclose(p.normal, -box_normal, atol=1e-7)
    check_conventions(p)
    np.testing.assert_allclose(p.point_a, centre + radius * p.normal, atol=1e-9)
    q = proximity(box, ball)  # swapped: same distance, normal reversed
    assert q.distance == pytest.approx(expected, abs=1e-9)
    np.testing.assert_allclose(q.normal, box_normal, atol=1e-7)
    np.testing.assert_allclose(q.point_b, p.point_a, atol=1e-9)
    check_conventions(q)


# ------------------------------------------------------------------ capsule vs box, apart
@pytest.mark.slow
@settings(max_examples=100, deadline=None)
@given(boxes, vec3, vec3, st.floats(0.01, 0.3))
def test_capsule_box_apart_matches_a_minimisation_along_the_axis(box, a, b, radius):
    a, b = 1.5 * a, 1.5 * b

    def along(t):
        return point_box_distance(a + t * (b - a), box)

    grid = np.linspace(0.0, 1.0, 201)
    j = int(np.argmin([along(t) for t in grid]))
    best = minimize_scalar(along, bounds=(grid[max(j - 1, 0)], grid[min(j + 1, 200)]),
                           method="bounded", options={"xatol": 1e-12})
    axis_distance = min(best.fun, along(0.0), along(1.0))
    assume(axis_distance > 1e-3)  # the axis outside the box: distance is convex along it
    p = proximity(Capsule(a, b, radius), box)
    assert p.distance == pytest.approx(axis_distance - radius, abs=1e-9)
    check_conventions(p)
    # point_b on the box's surface (inside, on a face), point_a on the capsule's
    local = np.abs(box_local(p.point_b, box))
    assert (local <= box.half_size + 1e-9).all()
    assert (box.half_size - local).min() == pytest.approx(0.0, abs=1e-9)
    assert point_segment_distance(p.point_a, a, b) == pytest.approx(radius, abs=1e-9)


# ------------------------------------------------------------------ overlapping: support functions
@pytest.mark.slow
@settings(max_examples=60, deadline=None)
@given(boxes, vec3, vec3, st.floats(0.01, 0.3))
def test_capsule_box_signed_distance_matches_support_functions(box, a, b, radius):
    a = 0.5 * a  # near the box: often overlapping
    b = a + 0.6 * b
    cap = Capsule(a, b, radius)
    p = proximity(cap, box)
    axis_distance = segment_box_distance(a, b, box)
    if axis_distance > 1e-6:  # the axis outside the box: the capsule is that much thinner
        expected = axis_distance - radius
    else:  # the axis meets the box: the penetration depth from the support functions
        axes = separating_axes(*box.pose[:3, :3].T, b - a)
        expected = support_signed_distance(capsule_support(cap), box_support(box), axes)
    assert p.distance == pytest.approx(expected, abs=1e-7)
    check_conventions(p)


@pytest.mark.slow
@settings(max_examples=60, deadline=None)
@given(boxes, boxes)
def test_box_box_signed_distance_matches_support_functions(box_a, box_b):
    p = proximity(box_a, box_b)
    expected = box_box_distance(box_a, box_b)
    if expected <= 1e-6:  # overlapping: the penetration depth from the support functions
        axes = separating_axes(*box_a.pose[:3, :3].T, *box_b.pose[:3, :3].T)
        expected = support_signed_distance(box_support(box_a), box_support(box_b), axes)
    assert p.distance == pytest.approx(expected, abs=1e-7)
    check_conventions(p)


def test_axis_aligned_boxes():
    a = Box([1.0, 1.0, 1.0])
    apart = proximity(a, Box([1.0, 1.0, 1.0], pose(np.zeros(3), [2.0, 0.5, 0.0])))
    assert apart.distance == pytest.approx(1.0, abs=1e-9)
    np.testing.assert_allclose(apart.normal, [1.0, 0.0, 0.0], atol=1e-9)
    corner = proximity(a, Box([1.0, 1.0, 1.0], pose(np.zeros(3), [2.0, 2.0, 0.0])))
    assert corner.distance == pytest.approx(np.sqrt(2.0), abs=1e-9)
    overlap = proximity(a, Box([1.0, 1.0, 1.0], pose(np.zeros(3), [0.0, 0.0, 0.7])))
    assert overlap.distance == pytest.approx(-0.3, abs=1e-9)
    np.testing.assert_allclose(overlap.normal, [0.0, 0.0, 1.0], atol=1e-9)


# ------------------------------------------------------------------ touching, coincident
def test_exactly_touching_box_pairs_get_the_face_normal():
    box = Box([2.0, 2.0, 2.0])
    p = proximity(sphere(0.5, [1.5, 0.0, 0.0]), box)
    assert p.distance == pytest.approx(0.0, abs=1e-12)
    np.testing.assert_allclose(p.normal, [-1.0, 0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(p.point_a, [1.0, 0.0, 0.0], atol=1e-12)
    q = proximity(box, Capsule([0.3, 0.0, 1.2], [0.3, 0.0, 3.0], 0.2))
    assert q.distance == pytest.approx(0.0, abs=1e-9)
    np.testing.assert_allclose(q.normal, [0.0, 0.0, 1.0], atol=1e-9)
    faces = proximity(box, Box([2.0, 2.0, 2.0], pose(np.zeros(3), [2.0, 0.0, 0.0])))
    assert faces.distance == pytest.approx(0.0, abs=1e-9)
    np.testing.assert_allclose(faces.normal, [1.0, 0.0, 0.0], atol=1e-9)


def test_penetrating_and_coincident_box_pairs_push_apart():
    box = Box([2.0, 2.0, 2.0])
    deep = proximity(box, sphere(0.5, [0.8, 0.0, 0.0]))
    assert deep.distance == pytest.approx(-0.7, abs=1e-9)
    np.testing.assert_allclose(deep.normal, [1.0, 0.0, 0.0], atol=1e-9)
    check_conventions(deep)
    centred = proximity(Box([2.0, 2.0, 2.0]), sphere(0.5))
    assert centred.distance == pytest.approx(-1.5, abs=1e-9)
    assert np.linalg.norm(centred.normal) == pytest.approx(1.0)
    assert np.abs(centred.normal).max() == pytest.approx(1.0)  # along a face normal
    same = proximity(Box([1.0, 2.0, 3.0]), Box([1.0, 2.0, 3.0]))
    assert same.distance == pytest.approx(-1.0, abs=1e-9)  # out through the thinnest side
    np.testing.assert_allclose(np.abs(same.normal), [1.0, 0.0, 0.0], atol=1e-9)
    check_conventions(same)


def test_coal_conventions_that_proximity_relies_on():
    """coal.distance: signed, nearest points in the world, normal from o1 to o2."""
    box = coal.Box(2.0, 2.0, 2.0)
    ball = coal.Sphere(0.5)
    identity = coal.Transform3s(np.eye(3), np.zeros(3))
    for x, depth in ((3.0, 1.5), (1.0, -0.5)):
        result = coal.DistanceResult()
        d = coal.distance(box, identity, ball, coal.Transform3s(np.eye(3), np.array([x, 0, 0])),
                          coal.DistanceRequest(), result)
        assert d == pytest.approx(depth)
        p1, p2 = np.array(result.getNearestPoint1()), np.array(result.getNearestPoint2())
        np.testing.assert_allclose(result.normal, [1.0, 0.0, 0.0], atol=1e-12)
        np.testing.assert_allclose(p2 - p1, d * np.array(result.normal), atol=1e-12)
    capsule = coal.Capsule(0.1, 1.0)  # radius, full length along local z
    assert capsule.halfLength == pytest.approx(0.5)


# ------------------------------------------------------------------ first-order rule
@settings(max_examples=40, deadline=None)
@given(boxes, vec3, vec3, st.floats(0.02, 0.3), st.tuples(*[st.floats(-1.0, 1.0)] * 6))
def test_box_distance_rate_is_normal_dot_witness_velocity(box, a, b, radius, xi):
    a, b = 1.5 * a, 1.5 * b
    cap = Capsule(a, b, radius)
    p = proximity(cap, box)
    assume(p.distance > 0.02)
    assume(np.linalg.norm(b - a) > 0.05)
    # unique witness points: the axis parallel to no face and no edge of the box (a flat
    # contact has a set of witness points, and the distance has only one-sided
    # derivatives there)
    u = (b - a) / np.linalg.norm(b - a)
    assume(np.abs(box.pose[:3, :3].T @ u).min() > 0.1)
    h = 1e-5

    def moved(sign):
        T = pin.exp6(pin.Motion(np.asarray(xi) * sign * h)).homogeneous
        return proximity(cap, box.placed(T)).distance

    rate = (moved(1.0) - moved(-1.0)) / (2 * h)
    v, w = np.array(xi[:3]), np.array(xi[3:])
    predicted = p.normal @ (v + np.cross(w, p.point_b))
    assert rate == pytest.approx(predicted, abs=1e-4)


def test_fallback_normal_rule_for_a_degenerate_coal_normal():
    """Used only if coal returns a normal that is not unit (never seen in these tests):
    the witness direction signed by the distance, else the centres' direction, else +z."""
    from dualarm_qp.geometry.distance import _fallback_normal

    np.testing.assert_allclose(_fallback_normal(np.array([0.0, 2.0, 0.0]), 2.0, np.ones(3)),
                               [0.0, 1.0, 0.0])
    np.testing.assert_allclose(_fallback_normal(np.array([0.0, 2.0, 0.0]), -2.0, np.ones(3)),
                               [0.0, -1.0, 0.0])
    np.testing.assert_allclose(_fallback_normal(np.zeros(3), 0.0, np.array([3.0, 0.0, 4.0])),
                               [0.6, 0.0, 0.8])
    np.testing.assert_array_equal(_fallback_normal(np.zeros(3), 0.0, np.zeros(3)), [0, 0, 1])
