"""The clearance checks' own distances (clearance_oracle) are right.

Known answers worked out by hand; then agreement with the library (a different method:
Lumelsky's clamping for capsules, coal for boxes) on seeded random shapes, nearly
parallel segments and overlapping shapes included: two independent computations that
agree to 1e-9 m.
"""

from __future__ import annotations

import numpy as np
import pytest
from clearance_oracle import Placed, box_box, segment_box, segment_segment, signed_distance
from scipy.spatial.transform import Rotation

from dualarm_qp.geometry.distance import capsule_proximities, proximity
from dualarm_qp.geometry.shapes import Box, Capsule

TOL = 1e-12
AGREE = 1e-9


def _one(f, *args) -> float:
    return float(f(*(np.atleast_2d(np.asarray(a, dtype=float)) for a in args))[0])


@pytest.mark.parametrize(("p0", "p1", "q0", "q1", "expected"), [
    # Skew and perpendicular, the common perpendicular inside both: its length.
    ([-1, 0, 0], [1, 0, 0], [0, -1, 0.3], [0, 1, 0.3], 0.3),
    # Crossing: 0.
    ([-1, 0, 0], [1, 0, 0], [0, -1, 0], [0, 1, 0], 0.0),
    # Parallel, overlapping along the axis: the gap between the lines.
    ([0, 0, 0], [2, 0, 0], [1, 0.5, 0], [3, 0.5, 0], 0.5),
    # Collinear and disjoint: end to end.
    ([0, 0, 0], [1, 0, 0], [1.25, 0, 0], [2, 0, 0], 0.25),
    # Perpendicular, the perpendicular's foot off the end of one: end to the line.
    ([0, 0, 0], [1, 0, 0], [2, -1, 0.4], [2, 1, 0.4], np.hypot(1.0, 0.4)),
    # A point and a segment; two points.
    ([0.5, 0.3, 0], [0.5, 0.3, 0], [0, 0, 0], [1, 0, 0], 0.3),
    ([1, 2, 3], [1, 2, 3], [1, 2, 5], [1, 2, 5], 2.0),
])
def test_segment_segment_known_answers(p0, p1, q0, q1, expected) -> None:
    assert abs(_one(segment_segment, p0, p1, q0, q1) - expected) < TOL
    assert abs(_one(segment_segment, q1, q0, p1, p0) - expected) < TOL  # symmetric


def _box(half, R=None, centre=(0, 0, 0)):
    R = np.eye(3) if R is None else R
    return (np.atleast_2d(np.asarray(centre, dtype=float)), np.asarray(R, dtype=float)[None],
            np.atleast_2d(np.asarray(half, dtype=float)))


@pytest.mark.parametrize(("p0", "p1", "expected"), [
    ([2, 0, 0], [2, 0, 0], 1.0),                       # a point in front of the x face
    ([2, 3, 4], [2, 3, 4], np.sqrt(1 + 1 + 1)),        # a point beyond the corner
    ([0, 0, 0], [0, 0, 0], -1.0),                      # the centre: depth to the nearest face
    ([0.8, 0, 0], [0.8, 0, 0], -0.2),                  # inside, 0.2 from the x face
    ([-5, 0, 0], [5, 0, 0], -2.0),                     # through along x: out along y, 2
    ([-5, 2.5, 3.5], [5, 2.5, 3.5], np.hypot(0.5, 0.5)),  # past an x edge
    ([-5, 2.5, 0], [5, 2.5, 0], 0.5),                  # along the y face, outside
])
def test_segment_box_known_answers(p0, p1, expected) -> None:
    """Box centred at the origin, half sizes (1, 2, 3)."""
    c, R, h = _box([1, 2, 3])
    got = float(segment_box(np.atleast_2d(p0), np.atleast_2d(p1), c, R, h)[0])
    assert abs(got - expected) < TOL


def test_segment_box_depth_needs_the_cross_axes() -> None:
    """A segment cutting a corner off a tall box (x + y = 1.8 through the square
    [-1, 1]^2): the way out is across the segment, 0.2 / sqrt(2) deep; the faces' axes
    alone would give 1.2. In a thin slab (half height 0.1) the way out is along z."""
    p0, p1 = np.array([[-0.2, 2.0, 0.0]]), np.array([[2.0, -0.2, 0.0]])
    tall = _box([1, 1, 5])
    assert abs(float(segment_box(p0, p1, *tall)[0]) + 0.2 / np.sqrt(2)) < TOL
    slab = _box([1, 1, 0.1])
    assert abs(float(segment_box(p0, p1, *slab)[0]) + 0.1) < TOL


def test_box_box_known_answers() -> None:
    unit = _box([0.5, 0.5, 0.5])
    # Apart along x by 0.3 (faces parallel).
    assert abs(_bb(unit, _box([0.5, 0.5, 0.5], centre=[1.3, 0.2, -0.1])) - 0.3) < TOL
    # A box turned 45 degrees about z, an edge towards the unit cube's x face.
    R = Rotation.from_euler("z", 45, degrees=True).as_matrix()
    turned = _box([0.5, 0.5, 0.5], R, centre=[0.5 + 0.5 * np.sqrt(2) + 0.25, 0, 0])
    assert abs(_bb(unit, turned) - 0.25) < TOL
    # Corner to corner along the diagonal.
    far = _box([0.5, 0.5, 0.5], centre=[1.5, 1.5, 1.5])
    assert abs(_bb(unit, far) - np.sqrt(3) * 0.5) < TOL
    # Overlapping by 0.1 along y (the shallowest axis).
    deep = _box([0.5, 0.5, 0.5], centre=[0.2, 0.9, 0.0])
    assert abs(_bb(unit, deep) + 0.1) < TOL
    # One box inside the other: depth to push it out along the nearest face.
    inner = _box([0.1, 0.1, 0.1], centre=[0.3, 0, 0])
    assert abs(_bb(unit, inner) + (0.5 - 0.3 + 0.1)) < TOL


def _bb(x, y) -> float:
    return float(box_box(*x, *y)[0])


# ------------------------------------------------------------------ against the library
def _random_segments(rng: np.random.Generator, k: int):
    p0, p1, q0, q1 = (rng.normal(size=(k, 3)) for _ in range(4))
    m = k // 4
    # Nearly parallel (angles down to 1e-9 rad), parallel, points and crossing segments.
    q1[:m] = q0[:m] + (p1[:m] - p0[:m]) * rng.uniform(0.2, 2, size=(m, 1)) + (
        10.0 ** rng.uniform(-12, -3, size=(m, 1))) * rng.normal(size=(m, 3))
    q1[m:m + 20] = q0[m:m + 20] + 0.5 * (p1[m:m + 20] - p0[m:m + 20])
    q1[m + 20:m + 40] = q0[m + 20:m + 40]
    p1[m + 40:m + 60] = p0[m + 40:m + 60]
    mid = 0.5 * (p0[m + 60:m + 80] + p1[m + 60:m + 80])
    q0[m + 60:m + 80] = mid - rng.normal(size=(20, 3))
    q1[m + 60:m + 80] = 2 * mid - q0[m + 60:m + 80]     # through p's midpoint
    return p0, p1, q0, q1


def test_capsules_agree_with_the_library() -> None:
    rng = np.random.default_rng(18)
    p0, p1, q0, q1 = _random_segments(rng, 2000)
    ra, rb = rng.uniform(0.01, 0.5, 2000), rng.uniform(0.01, 0.5, 2000)
    mine = signed_distance(Placed("capsule", a=p0, b=p1, radius=ra),
                           Placed("capsule", a=q0, b=q1, radius=rb))
    lib = capsule_proximities(p0, p1, ra, q0, q1, rb).distance
    assert (mine < 0).sum() > 300 and (mine > 0).sum() > 300  # both regimes are tested
    assert np.max(np.abs(mine - lib)) < AGREE


def test_capsule_box_and_box_box_agree_with_the_library() -> None:
    rng = np.random.default_rng(180)
    k = 300
    R = Rotation.random(k, random_state=3).as_matrix()
    half = rng.uniform(0.02, 0.5, (k, 3))
    centre = rng.normal(size=(k, 3)) * 0.6
    p0, p1 = rng.normal(size=(k, 3)) * 0.6, rng.normal(size=(k, 3)) * 0.6
    p1[:30] = p0[:30]                                    # spheres
    radius = rng.uniform(0.01, 0.3, k)
    caps = signed_distance(Placed("capsule", a=p0, b=p1, radius=radius),
                           Placed("box", centre=centre, R=R, half=half))
    R2 = Rotation.random(k, random_state=4).as_matrix()
    half2 = rng.uniform(0.02, 0.5, (k, 3))
    centre2 = rng.normal(size=(k, 3)) * 0.8
    boxes = signed_distance(Placed("box", centre=centre2, R=R2, half=half2),
                            Placed("box", centre=centre, R=R, half=half))
    lib_caps, lib_boxes = np.empty(k), np.empty(k)
    for i in range(k):
        T = np.eye(4)
        T[:3, :3], T[:3, 3] = R[i], centre[i]
        T2 = np.eye(4)
        T2[:3, :3], T2[:3, 3] = R2[i], centre2[i]
        box = Box(2 * half[i], T)
        lib_caps[i] = proximity(Capsule(p0[i], p1[i], radius[i]), box).distance
        lib_boxes[i] = proximity(Box(2 * half2[i], T2), box).distance
    for mine, lib in ((caps, lib_caps), (boxes, lib_boxes)):
        assert (mine < 0).sum() > 10 and (mine > 0).sum() > 10
        assert np.max(np.abs(mine - lib)) < AGREE


def test_the_distance_is_a_minimum() -> None:
    """No pair of points of the two segments is closer than the oracle says, and a fine
    grid of both parameters comes as close as its spacing allows."""
    rng = np.random.default_rng(7)
    p0, p1, q0, q1 = _random_segments(rng, 200)
    d = segment_segment(p0, p1, q0, q1)
    s = np.linspace(0.0, 1.0, 401)
    for i in range(0, 200, 10):
        P = p0[i] + s[:, None] * (p1[i] - p0[i])
        Q = q0[i] + s[:, None] * (q1[i] - q0[i])
        grid = np.sqrt(((P[:, None, :] - Q[None, :, :]) ** 2).sum(-1)).min()
        assert d[i] <= grid + 1e-15
        # A grid point lies within half a step of the minimiser in both parameters.
        assert grid - d[i] <= (np.linalg.norm(p1[i] - p0[i])
                               + np.linalg.norm(q1[i] - q0[i])) / 800 + 1e-12
