"""Capsule distances: the closed form against an exact oracle, normals that never vanish,
the first-order rule the rows use, and bad input."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from geom_oracles import point_segment_distance, segment_distance_exact
from hypothesis import assume, example, given, settings
from hypothesis import strategies as st

from dualarm_qp.errors import InvalidInputError, NonFiniteError, ShapeError
from dualarm_qp.geometry import (
    TOUCH_TOL,
    Capsule,
    capsule_proximities,
    proximity,
    segment_closest_points,
    sphere,
)

coord = st.floats(-1.0, 1.0, allow_nan=False, allow_infinity=False)
point = st.tuples(coord, coord, coord).map(np.array)
unit = st.floats(0.0, 1.0)
tiny = st.sampled_from([1e-3, 1e-6, 1e-9, 1e-12, 1e-15])


@st.composite
def segment_pair(draw):
    """Random, parallel, nearly parallel, collinear, zero-length and crossing segments."""
    kind = draw(st.sampled_from(["random", "parallel", "near_parallel", "collinear",
                                 "zero_a", "zero_b", "zero_both", "crossing",
                                 "near_parallel_crossing"]))
    p0, p1, q0, q1 = (draw(point) for _ in range(4))
    d1 = p1 - p0
    if kind == "parallel":
        q1 = q0 + draw(st.floats(-2.0, 2.0)) * d1
    elif kind == "near_parallel":
        q1 = q0 + draw(st.floats(-2.0, 2.0)) * d1 + draw(tiny) * draw(point)
    elif kind == "collinear":
        q0, q1 = p0 + draw(st.floats(-2.0, 2.0)) * d1, p0 + draw(st.floats(-2.0, 2.0)) * d1
    elif kind == "zero_a":
        p1 = p0.copy()
    elif kind == "zero_b":
        q1 = q0.copy()
    elif kind == "zero_both":
        p1, q1 = p0.copy(), q0.copy()
    elif kind in ("crossing", "near_parallel_crossing"):
        x, s0, t0 = draw(point), draw(unit), draw(unit)
        d2 = (q1 - q0 if kind == "crossing"
              else draw(st.floats(-2.0, 2.0)) * d1 + draw(tiny) * draw(point))
        p0, q0 = x - s0 * d1, x - t0 * d2
        p1, q1 = p0 + d1, q0 + d2
    return p0, p1, q0, q1


def rigid_motion(xi, h):
    """World pose after moving for time h with twist xi = (v, w) (about the origin)."""
    return pin.exp6(pin.Motion(np.asarray(xi) * h)).homogeneous


# ------------------------------------------------------------------ closed form vs oracle
@pytest.mark.slow
@settings(max_examples=400, deadline=None)
@given(st.lists(segment_pair(), min_size=1, max_size=6))
def test_segment_distance_matches_the_exact_oracle(pairs):
    p0, p1, q0, q1 = (np.array(v) for v in zip(*pairs, strict=True))
    s, t, x, y = segment_closest_points(p0, p1, q0, q1)
    assert ((s >= 0) & (s <= 1) & (t >= 0) & (t <= 1)).all()
    np.testing.assert_allclose(x, p0 + s[:, None] * (p1 - p0), atol=1e-15)
    np.testing.assert_allclose(y, q0 + t[:, None] * (q1 - q0), atol=1e-15)
    found = np.linalg.norm(x - y, axis=1)
    exact = [segment_distance_exact(*pair) for pair in pairs]
    np.testing.assert_allclose(found, exact, rtol=0, atol=1e-9)


def test_the_exact_oracle_agrees_with_dense_sampling():
    """The oracle itself: never above a dense grid's minimum, and within its resolution."""
    rng = np.random.default_rng(7)
    grid = np.linspace(0.0, 1.0, 801)
    for _ in range(20):
        p0, p1, q0, q1 = rng.normal(size=(4, 3))
        xs, ys = p0 + grid[:, None] * (p1 - p0), q0 + grid[:, None] * (q1 - q0)
        gap = xs[:, None, :] - ys[None, :, :]
        sampled = np.linalg.norm(gap, axis=2).min()
        exact = segment_distance_exact(p0, p1, q0, q1)
        step = (np.linalg.norm(p1 - p0) + np.linalg.norm(q1 - q0)) / 800
        assert exact <= sampled + 1e-12
        assert sampled - exact <= step


# ------------------------------------------------------------------ conventions
@pytest.mark.slow
@settings(max_examples=200, deadline=None)
@given(st.lists(st.tuples(segment_pair(), st.floats(0.0, 0.5), st.floats(0.0, 0.5)),
                min_size=1, max_size=6))
@example([((np.array([-0.5, 0.0, 0.0]), np.array([-0.375, 0.0, 1.0]),
            np.array([-0.5, 0.0, 0.0]), np.array([-0.5, 0.0, 1.30179878e-157])), 0.5, 0.5)])
def test_capsule_proximity_conventions(items):
    pairs = [pair for pair, _, _ in items]
    p0, p1, q0, q1 = (np.array(v) for v in zip(*pairs, strict=True))
    ra = np.array([r for _, r, _ in items])
    rb = np.array([r for _, _, r in items])
    prox = capsule_proximities(p0, p1, ra, q0, q1, rb)
    exact = np.array([segment_distance_exact(*pair) for pair in pairs])
    # signed distance: axis distance minus both radii
    np.testing.assert_allclose(prox.distance, exact - ra - rb, atol=1e-9)
    # a unit normal, always, and point_b - point_a = distance * normal
    np.testing.assert_allclose(np.linalg.norm(prox.normal, axis=1), 1.0, atol=1e-12)
    np.testing.assert_allclose(prox.point_b - prox.point_a,
                               prox.distance[:, None] * prox.normal, atol=1e-9)
    # witness points on the surfaces: at one radius from their own axis
    for i in range(len(prox)):
        assert point_segment_distance(prox.point_a[i], p0[i], p1[i]) == pytest.approx(
            ra[i], abs=1e-9)
        assert point_segment_distance(prox.point_b[i], q0[i], q1[i]) == pytest.approx(
            rb[i], abs=1e-9)
        single = proximity(Capsule(p0[i], p1[i], ra[i] + 1e-3),
                           Capsule(q0[i], q1[i], rb[i] + 1e-3))
        assert single.distance == pytest.approx(prox.distance[i] - 2e-3, abs=1e-12)
        np.testing.assert_allclose(single.normal, prox.normal[i], atol=1e-12)


@settings(max_examples=100, deadline=None)
@given(segment_pair(), st.floats(0.01, 0.5), st.floats(0.01, 0.5))
def test_swapping_the_shapes_flips_the_normal(pair, ra, rb):
    p0, p1, q0, q1 = pair
    assume(segment_distance_exact(*pair) > 1e-6)
    ab = proximity(Capsule(p0, p1, ra), Capsule(q0, q1, rb))
    ba = proximity(Capsule(q0, q1, rb), Capsule(p0, p1, ra))
    assert ab.distance == pytest.approx(ba.distance, abs=1e-12)
    np.testing.assert_allclose(ab.normal, -ba.normal, atol=1e-9)
    d1, d2 = p1 - p0, q1 - q0
    if np.linalg.norm(np.cross(d1, d2)) > 1e-3 * np.linalg.norm(d1) * np.linalg.norm(d2):
        # not parallel: the witness points are unique
        np.testing.assert_allclose(ab.point_a, ba.point_b, atol=1e-9)
        np.testing.assert_allclose(ab.point_b, ba.point_a, atol=1e-9)


# ------------------------------------------------------------------ touching, overlapping
def test_exactly_touching_capsules():
    a = Capsule([0, 0, 0], [1, 0, 0], 0.25)
    b = Capsule([0.5, -1, 0.5], [0.5, 1, 0.5], 0.25)
    p = proximity(a, b)
    assert p.distance == pytest.approx(0.0, abs=1e-15)
    np.testing.assert_allclose(p.normal, [0, 0, 1], atol=1e-15)
    np.testing.assert_allclose(p.point_a, [0.5, 0, 0.25], atol=1e-15)
    np.testing.assert_allclose(p.point_b, [0.5, 0, 0.25], atol=1e-15)


def test_penetrating_capsules_push_apart():
    a = Capsule([0, 0, 0], [1, 0, 0], 0.3)
    b = Capsule([0.5, -1, 0.2], [0.5, 1, 0.2], 0.3)
    p = proximity(a, b)
    assert p.distance == pytest.approx(0.2 - 0.6)
    np.testing.assert_allclose(p.normal, [0, 0, 1], atol=1e-15)
    np.testing.assert_allclose(p.point_a, [0.5, 0, 0.3], atol=1e-15)
    np.testing.assert_allclose(p.point_b, [0.5, 0, -0.1], atol=1e-15)


def test_crossing_axes_use_the_common_perpendicular_towards_b():
    a = Capsule([0, 0, 0], [1, 0, 0], 0.1)
    b = Capsule([0.5, -0.5, 0], [0.5, 1.5, 0], 0.1)  # crosses a at (0.5, 0, 0)
    p = proximity(a, b)
    assert p.distance == pytest.approx(-0.2, abs=1e-15)
    np.testing.assert_allclose(np.abs(p.normal), [0, 0, 1], atol=1e-15)
    # midpoints (0.5, 0, 0) and (0.5, 0.5, 0) tie along z: the + sign
    np.testing.assert_allclose(p.normal, [0, 0, 1], atol=1e-15)
    tilted = Capsule([0.5, -0.5, -0.5], [0.5, 1.5, 1.5], 0.1)  # crosses a at (0.5, 0, 0)
    q = proximity(a, tilted)
    expected = np.cross([1, 0, 0], [0, 2, 2]) / np.linalg.norm([0, 2, 2])
    if expected @ ((tilted.a + tilted.b) / 2 - (a.a + a.b) / 2) < 0:
        expected = -expected
    np.testing.assert_allclose(q.normal, expected, atol=1e-15)
    # moving b along the normal separates the axes at unit rate
    moved = Capsule(tilted.a + 1e-3 * q.normal, tilted.b + 1e-3 * q.normal, 0.1)
    assert proximity(a, moved).distance == pytest.approx(q.distance + 1e-3, abs=1e-12)


def test_axes_that_truly_cross_tie_to_the_plus_perpendicular():
    """Crossing axes lie in one plane: their midpoints' offset along the perpendicular is
    zero but for rounding, and the documented tie gives ``+ d1 x d2`` (in generic
    position too, where the offset's rounding has either sign)."""
    a = Capsule([2, 0, 1], [-1, 0, 0], 0.1)
    b = Capsule([-1, 0, 0], [0, -1, 0], 0.1)  # shares a's end: w . n = 0 exactly
    np.testing.assert_allclose(proximity(a, b).normal, np.array([-1, -1, 3]) / np.sqrt(11),
                               atol=1e-15)
    rng = np.random.default_rng(11)
    for _ in range(300):
        x = rng.normal(0.0, 1.0, 3)
        u, v = rng.normal(0.0, 1.0, (2, 3))
        s0, s1 = -rng.uniform(0.1, 1.0, 2)
        t0, t1 = rng.uniform(0.1, 1.0, 2)
        a = Capsule(x + s0 * u, x + t0 * u, 0.05)
        b = Capsule(x + s1 * v, x + t1 * v, 0.05)
        p = proximity(a, b)
        if p.distance > -0.1 + 1e-12:  # the rounded axes missed by more than TOUCH_TOL
            continue
        n = np.cross(a.b - a.a, b.b - b.a)
        np.testing.assert_allclose(p.normal, n / np.linalg.norm(n), atol=1e-12)


def test_t_contact_and_collinear_overlap_get_a_perpendicular_normal():
    a = Capsule([0, 0, 0], [1, 0, 0], 0.1)
    t_contact = proximity(a, Capsule([0.5, 0, 0], [0.5, 0, 1], 0.1))
    np.testing.assert_allclose(abs(t_contact.normal @ [1, 0, 0]), 0.0, atol=1e-15)
    np.testing.assert_allclose(abs(t_contact.normal @ [0, 0, 1]), 0.0, atol=1e-15)
    collinear = proximity(a, Capsule([0.5, 0, 0], [2.0, 0, 0], 0.1))
    assert collinear.distance == pytest.approx(-0.2)
    assert np.linalg.norm(collinear.normal) == pytest.approx(1.0)
    assert collinear.normal @ [1, 0, 0] == pytest.approx(0.0, abs=1e-15)
    point_on_axis = proximity(sphere(0.2, [0.3, 0, 0]), a)
    assert point_on_axis.distance == pytest.approx(-0.3)
    assert point_on_axis.normal @ [1, 0, 0] == pytest.approx(0.0, abs=1e-15)


def test_coincident_spheres_use_plus_z():
    p = proximity(sphere(0.1, [1, 2, 3]), sphere(0.2, [1, 2, 3]))
    assert p.distance == pytest.approx(-0.3)
    np.testing.assert_array_equal(p.normal, [0, 0, 1])
    np.testing.assert_allclose(p.point_b - p.point_a, -0.3 * np.array([0, 0, 1]))


def test_sphere_pairs_are_centre_distance_minus_radii():
    p = proximity(sphere(0.1, [0, 0, 0]), sphere(0.2, [3, 4, 0]))
    assert p.distance == pytest.approx(5.0 - 0.3)
    np.testing.assert_allclose(p.normal, [0.6, 0.8, 0.0])
    np.testing.assert_allclose(p.point_a, [0.06, 0.08, 0.0])
    np.testing.assert_allclose(p.point_b, [3 - 0.12, 4 - 0.16, 0.0])


@settings(max_examples=100, deadline=None)
@given(segment_pair())
def test_meeting_axes_never_give_a_zero_normal(pair):
    """Shift b so that its closest point lands exactly on a's: the normal stays unit."""
    p0, p1, q0, q1 = pair
    _, _, x, y = segment_closest_points(*(v[None] for v in pair))
    shift = (x - y)[0]
    prox = capsule_proximities(p0[None], p1[None], [0.1], (q0 + shift)[None],
                               (q1 + shift)[None], [0.1])
    assert np.isfinite(prox.normal).all()
    assert np.linalg.norm(prox.normal[0]) == pytest.approx(1.0, abs=1e-12)
    assert prox.distance[0] <= -0.2 + 1e-9


@pytest.mark.parametrize(("z", "normal"), [
    (10 * TOUCH_TOL, [0, 0, 1]),  # above the tolerance: the closest points' direction
    (-10 * TOUCH_TOL, [0, 0, -1]),
    (-TOUCH_TOL / 10, [0, 0, -1]),  # at or below: the rule, towards b's midpoint
    (0.0, [0, 0, 1]),  # midpoints level: the + sign
])
def test_normal_near_the_touch_tolerance(z, normal):
    a = Capsule([0, 0, 0], [1, 0, 0], 0.1)
    p = proximity(a, Capsule([0.5, -1, z], [0.5, 1, z], 0.1))
    np.testing.assert_allclose(p.normal, normal, atol=1e-12)
    assert p.distance == pytest.approx(abs(z) - 0.2, abs=1e-15)


# ------------------------------------------------------------------ first-order rule
@settings(max_examples=100, deadline=None)
@given(point, point, point, point, st.floats(0.01, 0.3), st.floats(0.01, 0.3),
       st.tuples(*[st.floats(-1.0, 1.0)] * 6), st.booleans())
@pytest.mark.slow
def test_distance_rate_is_normal_dot_witness_velocity(p0, p1, q0, q1, ra, rb, xi, move_a):
    d1, d2 = p1 - p0, q1 - q0
    assume(np.linalg.norm(np.cross(d1, d2)) > 1e-2 * max(np.linalg.norm(d1), 1e-9)
           * max(np.linalg.norm(d2), 1e-9))
    gap = segment_distance_exact(p0, p1, q0, q1)
    assume(gap > 5e-2)
    a, b = Capsule(p0, p1, ra), Capsule(q0, q1, rb)
    prox = proximity(a, b)
    v, w = np.array(xi[:3]), np.array(xi[3:])
    h = 1e-6

    def moved(sign):
        T = rigid_motion(xi, sign * h)
        if move_a:
            return proximity(a.placed(T), b).distance
        return proximity(a, b.placed(T)).distance

    rate = (moved(1.0) - moved(-1.0)) / (2 * h)
    if move_a:
        predicted = -prox.normal @ (v + np.cross(w, prox.point_a))
    else:
        predicted = prox.normal @ (v + np.cross(w, prox.point_b))
    # Central differences are exact to second order where the distance is smooth. Where
    # a witness sits on a segment's end and the motion takes it along the segment on one
    # side only (a kink), their error is up to speed^2 h / (4 gap), with speed a bound
    # on the points' speed: about 1e-6 for a unit speed at a gap of 0.25.
    speed = float(np.linalg.norm(v) + np.linalg.norm(w) * max(
        np.linalg.norm(x) for x in (p0, p1, q0, q1)))
    assert rate == pytest.approx(predicted, abs=1e-6 + speed ** 2 * h / (2 * gap))


# ------------------------------------------------------------------ input
@pytest.mark.filterwarnings("ignore:overflow encountered:RuntimeWarning",
                            "ignore:invalid value encountered:RuntimeWarning")
def test_batch_input_errors():
    z3, z = np.zeros((2, 3)), np.zeros(2)
    with pytest.raises(ShapeError, match="b1"):
        capsule_proximities(z3, z3, z, z3, np.zeros((3, 3)), z)
    with pytest.raises(ShapeError, match="radius_a"):
        capsule_proximities(z3, z3, np.zeros((2, 1)), z3, z3, z)
    with pytest.raises(ShapeError, match="radius_b"):
        capsule_proximities(z3, z3, z, z3, z3, np.zeros(3))
    bad = z3.copy()
    bad[1, 2] = np.nan
    with pytest.raises(NonFiniteError, match="a1"):
        capsule_proximities(z3, bad, z, z3 + 1, z3 + 1, z)
    far, x_axis = z3 + 1, z3 + np.array([1.0, 0.0, 0.0])
    far[0, 0] = -np.inf
    with pytest.raises(NonFiniteError, match="b0"):
        capsule_proximities(z3, x_axis, z, far, z3 + 1, z)
    with pytest.raises(NonFiniteError, match="b1"):
        capsule_proximities(z3, x_axis, z, z3 + 1, far, z)
    with pytest.raises(InvalidInputError, match="too large"):
        capsule_proximities(z3, z3 + 1e200, z, z3 - 1e200, z3, z)
    with pytest.raises(NonFiniteError, match="radius_b"):
        capsule_proximities(z3, z3, z, z3 + 1, z3 + 1, [0.1, np.inf])
    with pytest.raises(InvalidInputError, match="non-negative"):
        capsule_proximities(z3, z3, [0.1, -0.1], z3 + 1, z3 + 1, z)
    with pytest.raises(InvalidInputError, match="Capsule or a Box"):
        proximity(Capsule([0, 0, 0], [1, 0, 0], 0.1), "box")


def test_empty_batch():
    prox = capsule_proximities(np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0),
                               np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0))
    assert len(prox) == 0 and prox.normal.shape == (0, 3)
