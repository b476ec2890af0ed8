"""Distance between two placed shapes, with witness points and a unit normal.

Conventions (the same for every pair, and the same as coal's):

* ``distance`` is *signed*: positive when the shapes are apart, zero when they touch,
  negative when they overlap. For capsules (and spheres) it is the distance between
  the two axis segments minus both radii; for pairs with a box it is coal's signed
  distance (minus the penetration depth when they overlap).
* ``normal`` is a unit vector from shape a to shape b: translating b by ``h normal``
  (or a by ``-h normal``) changes the distance by ``+h`` to first order. It is never
  zero, even for touching or overlapping shapes (see *Normal when the axes meet*).
* ``point_a`` lies on the surface of a and ``point_b`` on the surface of b, and
  ``point_b - point_a = distance * normal`` (for overlapping shapes the two points are
  the deepest points, and ``point_b`` lies *behind* ``point_a`` along the normal).
* All points and vectors are in the frame the shapes were placed in (the world) [m].

The first-order rule the velocity-damper rows rely on: if shape a moves rigidly with
velocity field ``v_a(p)`` and shape b with ``v_b(p)``, the distance changes at the rate
``normal . (v_b(point_b) - v_a(point_a))`` wherever the nearest points are unique.

Capsule pairs (:func:`capsule_proximities`) use a closed form for the closest points
of two segments ``p0 + s d1`` and ``q0 + t d2``, ``(s, t)`` in ``[0, 1]^2``, vectorised
over many pairs: the parameter ``t`` of the two lines' common perpendicular, clamped to
[0, 1]; then the best ``s`` for that ``t`` (clamped), the best ``t`` for that ``s``
(clamped) and once more the best ``s`` (the clamping sequence of Lumelsky 1985, as in
Ericson, *Real-Time Collision Detection*, 5.1.9). The line parameter is computed as
``t = r' . w / |w|^2`` with ``r = p0 - q0``, and ``r'`` and ``w`` the vectors ``r`` and
``d2`` with their parts along ``d1`` removed: removing them before the product keeps
``t`` accurate for nearly parallel segments (the tests compare the distance with exact
rational arithmetic to 1e-9 m, nearly parallel and crossing segments included; the
largest error seen at metre scale is about 2e-15 m). Exactly parallel segments start
from ``t = 0``, and a zero-length segment keeps its parameter at 0.

Normal when the axes meet (axis distance at most :data:`TOUCH_TOL`), in order:

1. axes not parallel (the sine of their angle above 1e-9): the unit common
   perpendicular ``d1 x d2 / |d1 x d2|``, signed so that it points from a's midpoint
   towards b's midpoint (``+`` on a tie);
2. otherwise (parallel, or one segment a point): a fixed unit vector perpendicular to
   a's axis (to b's if a is a point): the cross product of the axis with the coordinate
   axis it is least aligned with, normalised;
3. both segments are points (two concentric spheres): ``+z``.

Pairs with a box go through coal (:func:`proximity`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import coal  # type: ignore[import-untyped]
import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidInputError, NonFiniteError, ShapeError
from .shapes import Box, Capsule

FloatArray = NDArray[np.float64]

#: Axis distance [m] at or below which two capsule axes count as meeting: the normal
#: then follows the rule of the module docstring instead of the (noisy) difference of
#: the closest points.
TOUCH_TOL = 1e-12


@dataclass(frozen=True, eq=False)
class Proximity:
    """Signed distance between two shapes, their witness points and the unit normal.

    Attributes
    ----------
    distance : float
        Signed distance [m]: positive apart, negative overlapping.
    point_a, point_b : ndarray, shape (3,)
        Witness points on the surfaces of a and b [m];
        ``point_b - point_a = distance * normal``.
    normal : ndarray, shape (3,)
        Unit vector from a to b along which the distance grows.
    """

    distance: float
    point_a: FloatArray
    point_b: FloatArray
    normal: FloatArray


@dataclass(frozen=True, eq=False)
class Proximities:
    """Proximities of k pairs at once (see :class:`Proximity`).

    Attributes
    ----------
    distance : ndarray, shape (k,)
        Signed distances [m].
    point_a, point_b : ndarray, shape (k, 3)
        Witness points on a and b [m].
    normal : ndarray, shape (k, 3)
        Unit normals from a to b.
    """

    distance: FloatArray
    point_a: FloatArray
    point_b: FloatArray
    normal: FloatArray

    def __len__(self) -> int:
        return int(self.distance.shape[0])

    def __getitem__(self, i: int) -> Proximity:
        """Return the proximity of pair ``i``."""
        return Proximity(float(self.distance[i]), self.point_a[i], self.point_b[i],
                         self.normal[i])


# ---------------------------------------------------------------- capsule pairs
def segment_closest_points(
    p0: Any, p1: Any, q0: Any, q1: Any
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Closest points of k pairs of segments ``[p0, p1]`` and ``[q0, q1]`` (vectorised).

    Parameters
    ----------
    p0, p1 : ndarray, shape (k, 3)
        Endpoints of the first segments [m] (``p0 == p1`` is a point).
    q0, q1 : ndarray, shape (k, 3)
        Endpoints of the second segments [m].

    Returns
    -------
    s, t : ndarray, shape (k,)
        Parameters in [0, 1] of the closest points (not unique for parallel segments:
        one of the closest pairs is returned).
    x, y : ndarray, shape (k, 3)
        The closest points ``p0 + s (p1 - p0)`` and ``q0 + t (q1 - q0)`` [m].
    """
    P0, P1, Q0, Q1 = (np.asarray(v, dtype=np.float64).T for v in (p0, p1, q0, q1))
    s, t, X, Y = _closest(P0, P1, Q0, Q1)
    return s, t, X.T, Y.T


def _closest(P0: FloatArray, P1: FloatArray, Q0: FloatArray,
             Q1: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """:func:`segment_closest_points` on components first: arrays (3, k), points (3, k).

    Every operation is one numpy call over all pairs (there is no loop over pairs).
    """
    d1, d2, r = P1 - P0, Q1 - Q0, P0 - Q0
    a = (d1 * d1).sum(0)
    e = (d2 * d2).sum(0)
    b = (d1 * d2).sum(0)
    c = (d1 * r).sum(0)
    f = (d2 * r).sum(0)
    a_safe = a + (a == 0.0)  # a == 0: d1 = 0, so b = c = 0 and s stays 0
    e_safe = e + (e == 0.0)  # e == 0: d2 = 0, so b = f = 0 and t stays 0
    # Stationary t of the two lines, from r and d2 with their parts along d1 removed
    # (removing r's part first keeps t accurate for nearly parallel segments).
    perp = d2 - (b / a_safe) * d1
    pp = (perp * perp).sum(0)
    t = _unit_clip(((r - (c / a_safe) * d1) * perp).sum(0) / (pp + (pp == 0.0)))
    # Clamp, then the best s for that t, the best t for that s, the best s for that t.
    s = _unit_clip((t * b - c) / a_safe)
    t = _unit_clip((s * b + f) / e_safe)
    s = _unit_clip((t * b - c) / a_safe)
    return s, t, P0 + s * d1, Q0 + t * d2


def _unit_clip(x: FloatArray) -> FloatArray:
    """Clip ``x`` to [0, 1] in place (two ufunc calls: cheaper than ``np.clip``)."""
    np.maximum(x, 0.0, out=x)
    np.minimum(x, 1.0, out=x)
    return x


def capsule_proximities(
    a0: Any, a1: Any, radius_a: Any, b0: Any, b1: Any, radius_b: Any
) -> Proximities:
    """Proximities of k capsule pairs, vectorised (the closed form of the module).

    Parameters
    ----------
    a0, a1 : array_like, shape (k, 3)
        Axis endpoints of the capsules a, in one common frame [m].
    radius_a : array_like, shape (k,)
        Radii of the capsules a [m], non-negative (zero: the bare segment).
    b0, b1 : array_like, shape (k, 3)
        Axis endpoints of the capsules b [m].
    radius_b : array_like, shape (k,)
        Radii of the capsules b [m], non-negative.

    Returns
    -------
    Proximities
        Signed distances (axis distance minus both radii), witness points on the
        surfaces and unit normals from a to b.

    Raises
    ------
    ShapeError
        Arrays of inconsistent shapes.
    InvalidInputError
        NaN or infinite values, or a negative radius.
    """
    a0, a1, b0, b1 = (np.asarray(v, dtype=np.float64) for v in (a0, a1, b0, b1))
    ra = np.asarray(radius_a, dtype=np.float64)
    rb = np.asarray(radius_b, dtype=np.float64)
    _check_shapes(a0, a1, ra, b0, b1, rb)
    if ra.shape[0] == 0:
        return Proximities(np.zeros(0), np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 3)))
    _, _, X, Y = _closest(a0.T, a1.T, b0.T, b1.T)
    gap = Y - X
    axis = np.sqrt((gap * gap).sum(0))
    distance = axis - ra - rb
    if not math.isfinite(float(distance.sum())):  # a NaN or infinity anywhere lands here
        _raise_non_finite(a0, a1, ra, b0, b1, rb)
    if ra.min() < 0.0 or rb.min() < 0.0:
        raise InvalidInputError("capsule radii must be non-negative [m], got "
                                f"{min(ra.min(), rb.min())!r}")
    meet = axis <= TOUCH_TOL
    normal = gap / (axis + meet)
    if meet.any():
        normal[:, meet] = _meeting_normal(a0[meet], a1[meet], b0[meet], b1[meet]).T
    return Proximities(distance, (X + ra * normal).T, (Y - rb * normal).T, normal.T)


def _meeting_normal(a0: FloatArray, a1: FloatArray, b0: FloatArray,
                    b1: FloatArray) -> FloatArray:
    """Return unit normals for pairs whose axes meet (the rule of the module docstring)."""
    d1, d2 = a1 - a0, b1 - b0
    n = _cross(d1, d2)
    n_len = np.sqrt(_dot(n, n))
    len1, len2 = np.sqrt(_dot(d1, d1)), np.sqrt(_dot(d2, d2))
    crossing = n_len > 1e-9 * len1 * len2
    out = np.empty_like(d1)
    if crossing.any():
        w = (b0 + b1 - a0 - a1)[crossing]
        # Scaled by its largest component first: the cross product of a very short axis
        # squares into subnormal numbers, whose square root is off by 1e-9 and more.
        nc = n[crossing] / np.abs(n[crossing]).max(axis=1, keepdims=True)
        nc /= np.sqrt(_dot(nc, nc))[:, None]
        out[crossing] = np.where(_dot(w, nc)[:, None] < 0.0, -nc, nc)
    rest = ~crossing
    if rest.any():
        axis = np.where((len1 > 0.0)[:, None], d1, d2)[rest]
        out[rest] = _perpendicular(axis)
    return out


def _perpendicular(axis: FloatArray) -> FloatArray:
    """Return a fixed unit vector perpendicular to each row of ``axis`` (``+z`` if zero)."""
    out = np.tile(np.array([0.0, 0.0, 1.0]), (axis.shape[0], 1))
    length = np.sqrt(_dot(axis, axis))
    some = length > 0.0
    if some.any():
        u = axis[some] / length[some, None]
        helper = np.zeros_like(u)
        helper[np.arange(u.shape[0]), np.argmin(np.abs(u), axis=1)] = 1.0
        v = _cross(u, helper)
        out[some] = v / np.sqrt(_dot(v, v))[:, None]
    return out


_BATCH_NAMES = ("a0", "a1", "radius_a", "b0", "b1", "radius_b")


def _check_shapes(a0: FloatArray, a1: FloatArray, ra: FloatArray, b0: FloatArray,
                  b1: FloatArray, rb: FloatArray) -> None:
    """Raise :class:`ShapeError` unless the arguments are k 3-vectors and k radii each."""
    if ra.ndim != 1:
        raise ShapeError("radius_a", (-1,), ra.shape)
    k = ra.shape[0]
    for name, arr, shape in zip(_BATCH_NAMES, (a0, a1, ra, b0, b1, rb),
                                ((k, 3), (k, 3), (k,), (k, 3), (k, 3), (k,)), strict=True):
        if arr.shape != shape:
            raise ShapeError(name, shape, arr.shape)


def _raise_non_finite(*arrays: FloatArray) -> None:
    """Name the first argument holding NaN or infinity (or a result that overflowed)."""
    for name, arr in zip(_BATCH_NAMES, arrays, strict=True):
        if not np.isfinite(arr).all():
            raise NonFiniteError(name)
    raise InvalidInputError("capsule coordinates are too large: the distances overflow")


def _dot(x: FloatArray, y: FloatArray) -> FloatArray:
    """Row-wise dot products of (k, 3) arrays."""
    out: FloatArray = np.einsum("ki,ki->k", x, y)
    return out


def _cross(x: FloatArray, y: FloatArray) -> FloatArray:
    """Row-wise cross products of (k, 3) arrays."""
    out = np.empty_like(x)
    out[:, 0] = x[:, 1] * y[:, 2] - x[:, 2] * y[:, 1]
    out[:, 1] = x[:, 2] * y[:, 0] - x[:, 0] * y[:, 2]
    out[:, 2] = x[:, 0] * y[:, 1] - x[:, 1] * y[:, 0]
    return out


# ---------------------------------------------------------------- any pair
def proximity(shape_a: Capsule | Box, shape_b: Capsule | Box) -> Proximity:
    """Signed distance, witness points and normal of two shapes placed in one frame.

    Capsule (and sphere) pairs use the closed form of :func:`capsule_proximities`; a
    pair with a box goes through coal's ``distance`` (GJK/EPA, or coal's own closed
    forms where it has them), with its tolerances tightened to 1e-10. Coal's nearest
    points and normal already follow this module's conventions; should coal return a
    degenerate normal, the normal falls back to the direction between the witness
    points, then between the shapes' centres, then ``+z``.

    Parameters
    ----------
    shape_a, shape_b : Capsule or Box
        The two shapes, both placed in the same frame (see ``placed``).

    Returns
    -------
    Proximity

    Raises
    ------
    InvalidInputError
        An argument is not a :class:`Capsule` or a :class:`Box`.
    """
    for name, shape in (("shape_a", shape_a), ("shape_b", shape_b)):
        if not isinstance(shape, Capsule | Box):
            raise InvalidInputError(f"{name} must be a Capsule or a Box, "
                                    f"got {type(shape).__name__}")
    if isinstance(shape_a, Capsule) and isinstance(shape_b, Capsule):
        return capsule_proximities(shape_a.a[None], shape_a.b[None], [shape_a.radius],
                                   shape_b.a[None], shape_b.b[None], [shape_b.radius])[0]
    return _coal_proximity(shape_a, shape_b)


def _coal_proximity(shape_a: Capsule | Box, shape_b: Capsule | Box) -> Proximity:
    """:func:`proximity` through ``coal.distance``."""
    geom_a, T_a = coal_shape(shape_a)
    geom_b, T_b = coal_shape(shape_b)
    return coal_proximity(geom_a, T_a, geom_b, T_b)


def coal_proximity(geom_a: Any, T_a: FloatArray, geom_b: Any, T_b: FloatArray) -> Proximity:
    """Signed distance, witness points and normal of two coal geometries.

    The same conventions as :func:`proximity` (which calls it for pairs with a box);
    for callers that keep their coal geometries across calls (the collision scene).

    Parameters
    ----------
    geom_a, geom_b : coal.CollisionGeometry
        The geometries, in their own frames (:func:`coal_shape`).
    T_a, T_b : ndarray, shape (4, 4)
        Their poses in the world [m].
    """
    request = coal.DistanceRequest()
    request.gjk_tolerance = 1e-10
    request.epa_tolerance = 1e-10
    result = coal.DistanceResult()
    distance = float(coal.distance(geom_a, coal.Transform3s(T_a[:3, :3], T_a[:3, 3]),
                                   geom_b, coal.Transform3s(T_b[:3, :3], T_b[:3, 3]),
                                   request, result))
    point_a = np.array(result.getNearestPoint1(), dtype=np.float64)
    point_b = np.array(result.getNearestPoint2(), dtype=np.float64)
    normal = np.array(result.normal, dtype=np.float64)
    length = float(np.linalg.norm(normal)) if np.isfinite(normal).all() else 0.0
    if abs(length - 1.0) > 1e-6:
        normal = _fallback_normal(point_b - point_a, distance, T_b[:3, 3] - T_a[:3, 3])
    else:
        normal /= length
    return Proximity(distance, point_a, point_b, normal)


def _fallback_normal(gap: FloatArray, distance: float, centres: FloatArray) -> FloatArray:
    """Witness-point direction (signed by the distance), else centre direction, else +z."""
    for v in (gap * (1.0 if distance >= 0.0 else -1.0), centres):
        length = float(np.linalg.norm(v))
        if length > TOUCH_TOL:
            return v / length
    return np.array([0.0, 0.0, 1.0])


def coal_shape(shape: Capsule | Box) -> tuple[Any, FloatArray]:
    """Coal geometry of a shape and the pose (4, 4) of that geometry in the shape's frame.

    Coal's capsule lies along its local z axis, centred on its origin; a zero-length
    capsule is a coal sphere; a box is centred on its pose.
    """
    if isinstance(shape, Box):
        return coal.Box(*shape.size.tolist()), np.array(shape.pose)
    axis = shape.b - shape.a
    length = float(np.linalg.norm(axis))
    T = np.eye(4)
    T[:3, 3] = (shape.a + shape.b) / 2.0
    if length == 0.0:
        return coal.Sphere(shape.radius), T
    T[:3, :3] = _frame_with_z(axis / length)
    return coal.Capsule(shape.radius, length), T


def _frame_with_z(z: FloatArray) -> FloatArray:
    """Return a rotation matrix whose third column is the unit vector ``z``."""
    x = _perpendicular(z[None])[0]
    return np.column_stack([x, np.cross(z, x), z])
