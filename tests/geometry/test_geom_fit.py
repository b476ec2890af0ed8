"""Fitted capsules contain what they stand for: point sets, coal primitives and meshes."""

from __future__ import annotations

import coal
import numpy as np
import pinocchio as pin
import pytest
from geom_oracles import point_segment_distance
from hypothesis import given, settings
from hypothesis import strategies as st

from dualarm_qp.errors import InvalidInputError, NonFiniteError, ShapeError
from dualarm_qp.geometry import Capsule, fit_capsule, geometry_balls
from dualarm_qp.geometry.fit import FIT_MARGIN


def pose(rotvec, p):
    T = np.eye(4)
    T[:3, :3] = pin.exp3(np.asarray(rotvec, dtype=float))
    T[:3, 3] = p
    return T


def excess(cap: Capsule, points, radii=None) -> float:
    """Largest amount by which a ball sticks out of the capsule [m] (<= 0: contained)."""
    radii = np.zeros(len(points)) if radii is None else radii
    return max(point_segment_distance(p, cap.a, cap.b) + r - cap.radius
               for p, r in zip(points, radii, strict=True))


def capsule_volume(cap: Capsule) -> float:
    return np.pi * cap.radius**2 * cap.length + 4.0 / 3.0 * np.pi * cap.radius**3


def random_directions(rng, n):
    v = rng.normal(size=(n, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


# ------------------------------------------------------------------ point sets
@st.composite
def clouds(draw):
    n = draw(st.integers(1, 40))
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    kind = draw(st.sampled_from(["blob", "rod", "flat", "line", "same"]))
    scale = {"blob": [1, 1, 1], "rod": [1, 0.05, 0.05], "flat": [1, 1, 0],
             "line": [1, 0, 0], "same": [0, 0, 0]}[kind]
    pts = rng.normal(size=(n, 3)) * scale @ pin.exp3(rng.normal(size=3)).T + rng.normal(size=3)
    radii = rng.uniform(0, 0.2, n) if draw(st.booleans()) else None
    return pts, radii


@pytest.mark.slow
@settings(max_examples=80, deadline=None)
@given(clouds())
def test_fitted_capsule_contains_every_ball(cloud):
    pts, radii = cloud
    cap = fit_capsule(pts, radii)
    assert excess(cap, pts, radii) <= 0.0
    assert excess(cap, pts, radii) >= -FIT_MARGIN - 1e-6 * cap.radius  # and touches one


def test_fit_recovers_a_sampled_capsule():
    rng = np.random.default_rng(3)
    R = pin.exp3(rng.normal(size=3))
    a, b, radius = np.array([0.0, 0.0, -0.2]), np.array([0.0, 0.0, 0.2]), 0.05
    # the surface, densely: the side and both caps
    t = rng.uniform(0, 1, 3000)
    ring = random_directions(rng, 3000) * [1, 1, 0]
    ring /= np.linalg.norm(ring, axis=1, keepdims=True)
    side = a + t[:, None] * (b - a) + radius * ring
    caps = np.vstack([a + radius * random_directions(rng, 1000),
                      b + radius * random_directions(rng, 1000)])
    pts = np.vstack([side, caps]) @ R.T + [0.3, -0.2, 0.1]
    cap = fit_capsule(pts)
    assert excess(cap, pts) <= 0.0
    assert cap.radius == pytest.approx(radius, rel=0.02)
    assert capsule_volume(cap) <= 1.05 * capsule_volume(Capsule(a, b, radius))
    axis = (cap.b - cap.a) / cap.length
    assert abs(axis @ R[:, 2]) == pytest.approx(1.0, abs=1e-3)


def test_one_point_and_one_ball_give_spheres():
    point = fit_capsule([[1.0, 2.0, 3.0]])
    assert point.is_sphere and point.radius == pytest.approx(FIT_MARGIN)
    np.testing.assert_allclose(point.a, [1.0, 2.0, 3.0])
    ball = fit_capsule([[1.0, 2.0, 3.0]], [0.3])
    assert ball.radius == pytest.approx(0.3 + FIT_MARGIN)


@pytest.mark.parametrize(("points", "radii", "error", "text"), [
    (np.zeros((0, 3)), None, InvalidInputError, "at least one"),
    (np.zeros((4, 2)), None, ShapeError, "points"),
    ([[0, 0, np.nan]], None, NonFiniteError, "points"),
    (np.zeros((2, 3)), [0.1], ShapeError, "radii"),
    (np.zeros((2, 3)), [0.1, -0.1], InvalidInputError, "non-negative"),
])
def test_fit_rejects_bad_input(points, radii, error, text):
    with pytest.raises(error, match=text):
        fit_capsule(points, radii)


# ------------------------------------------------------------------ coal primitives
def surface_samples(geometry, rng, n=4000):
    """Points on the surface of a coal primitive, sampled from its own parameters."""
    if isinstance(geometry, coal.Sphere):
        return geometry.radius * random_directions(rng, n)
    if isinstance(geometry, coal.Box):
        h = np.array(geometry.halfSide)
        pts = rng.uniform(-1, 1, size=(n, 3)) * h
        face = rng.integers(0, 3, n)
        pts[np.arange(n), face] = np.sign(rng.uniform(-1, 1, n)) * h[face]
        corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * h
        return np.vstack([pts, corners])
    if isinstance(geometry, coal.Cylinder):
        r, h = geometry.radius, geometry.halfLength
        phi = rng.uniform(0, 2 * np.pi, n)
        z = rng.uniform(-h, h, n)
        z[: n // 4] = np.sign(z[: n // 4]) * h  # the rims
        return np.column_stack([r * np.cos(phi), r * np.sin(phi), z])
    if isinstance(geometry, coal.Capsule):
        r, h = geometry.radius, geometry.halfLength
        phi = rng.uniform(0, 2 * np.pi, n)
        side = np.column_stack([r * np.cos(phi), r * np.sin(phi), rng.uniform(-h, h, n)])
        d = random_directions(rng, n)
        ends = r * d + np.outer(np.sign(d[:, 2]) * h, [0, 0, 1])
        return np.vstack([side, ends])
    if isinstance(geometry, coal.Cone):
        r, h = geometry.radius, geometry.halfLength
        phi, u = rng.uniform(0, 2 * np.pi, n), rng.uniform(0, 1, n)
        return np.column_stack([(1 - u) * r * np.cos(phi), (1 - u) * r * np.sin(phi),
                                -h + 2 * h * u])
    if isinstance(geometry, coal.Ellipsoid):
        return random_directions(rng, n) * np.array(geometry.radii)
    raise AssertionError(type(geometry))


@pytest.mark.parametrize("geometry", [
    coal.Sphere(0.2), coal.Box(0.1, 0.3, 0.5), coal.Cylinder(0.09, 0.283),
    coal.Capsule(0.05, 0.4), coal.Cone(0.1, 0.3), coal.Ellipsoid(0.1, 0.2, 0.05),
], ids=lambda g: type(g).__name__)
def test_primitive_balls_bound_the_primitive(geometry):
    rng = np.random.default_rng(5)
    T = pose(rng.normal(size=3), rng.normal(size=3))
    centres, radii = geometry_balls(geometry, T)
    cap = fit_capsule(centres, radii)
    surface = surface_samples(geometry, rng) @ T[:3, :3].T + T[:3, 3]
    assert excess(cap, surface) <= 0.0


def test_primitives_convert_exactly_where_they_can():
    T = pose([0.3, -0.2, 0.5], [1.0, 2.0, 3.0])
    ball = fit_capsule(*geometry_balls(coal.Sphere(0.2), T))
    assert ball.is_sphere and ball.radius == pytest.approx(0.2, abs=1e-8)
    np.testing.assert_allclose(ball.a, [1.0, 2.0, 3.0], atol=1e-12)
    rod = fit_capsule(*geometry_balls(coal.Capsule(0.05, 0.4), T))
    assert rod.radius == pytest.approx(0.05, abs=1e-8)
    assert rod.length == pytest.approx(0.4, abs=1e-6)
    swept = coal.Box(0.1, 0.1, 0.1)
    swept.setSweptSphereRadius(0.02)
    _, radii = geometry_balls(swept)
    np.testing.assert_array_equal(radii, 0.02)


def test_unbounded_geometry_is_rejected():
    with pytest.raises(InvalidInputError, match="Halfspace"):
        geometry_balls(coal.Halfspace(np.array([0.0, 0.0, 1.0]), 0.0))
