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

Capsule pairs (:func:`capsule_proximities`) use a closed form for the closest points of
two segments ``p0 + s d1`` and ``q0 + t d2``, ``(s, t)`` in ``[0, 1]^2``, compiled
(``src/kernel/capsules.cpp``, one call for many pairs): the parameter ``t`` of the two
lines' common perpendicular, clamped to [0, 1]; then the best ``s`` for that ``t``
(clamped), the best ``t`` for that ``s`` (clamped) and once more the best ``s`` (the
clamping sequence of Lumelsky 1985, as in Ericson, *Real-Time Collision Detection*,
5.1.9). The line parameter is computed as ``t = r' . w / |w|^2`` with ``r = p0 - q0``,
and ``r'`` and ``w`` the vectors ``r`` and ``d2`` with their parts along ``d1`` removed:
removing them before the product keeps ``t`` accurate for nearly parallel segments (the
tests compare the distance with exact rational arithmetic to 1e-9 m, nearly parallel and
crossing segments included; the largest error seen at metre scale is about 2e-15 m).
Exactly parallel segments start from ``t = 0``, and a zero-length segment keeps its
parameter at 0.

Normal when the axes meet (axis distance at most :data:`TOUCH_TOL`), in order:

1. axes not parallel (the sine of their angle above 1e-9): the unit common
   perpendicular ``d1 x d2 / |d1 x d2|``, signed so that it points from a's midpoint
   towards b's midpoint (``+`` on a tie: axes that truly cross lie in one plane, and
   an offset along the perpendicular within sixteen ulps of the endpoints' summed
   absolute coordinates is rounding);
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

from .._compiled import kernel
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
    """Closest points of k pairs of segments ``[p0, p1]`` and ``[q0, q1]``.

    The closed form of the module docstring, in the compiled kernel
    (``src/kernel/capsules.cpp``), one call for all pairs.

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

    Raises
    ------
    ShapeError
        An array that is not k 3-vectors.
    InvalidInputError
        Arrays of k that do not broadcast.
    """
    ends = [np.asarray(v, dtype=np.float64) for v in (p0, p1, q0, q1)]
    for name, arr in zip(("p0", "p1", "q0", "q1"), ends, strict=True):
        if arr.ndim != 2 or arr.shape[1] != 3:
            raise ShapeError(name, (-1, 3), arr.shape)
    try:
        wide = np.broadcast_arrays(*ends)
    except ValueError as err:
        shapes = ", ".join(str(a.shape) for a in ends)
        raise InvalidInputError(f"segment ends p0, p1, q0, q1 of shapes {shapes} do not "
                                "broadcast to one (k, 3)") from err
    c = kernel.segment_closest_points(*(np.ascontiguousarray(a) for a in wide))
    return c.s, c.t, c.x, c.y


def capsule_proximities(
    a0: Any, a1: Any, radius_a: Any, b0: Any, b1: Any, radius_b: Any
) -> Proximities:
    """Proximities of k capsule pairs (the closed form of the module, compiled).

    One kernel call for all pairs (``src/kernel/capsules.cpp``); the scene's
    :meth:`~dualarm_qp.collision.CollisionScene.measure` calls the same code.

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
    a0, a1, b0, b1 = (np.ascontiguousarray(v, dtype=np.float64) for v in (a0, a1, b0, b1))
    ra = np.asarray(radius_a, dtype=np.float64)
    rb = np.asarray(radius_b, dtype=np.float64)
    _check_shapes(a0, a1, ra, b0, b1, rb)
    p = kernel.capsule_proximities(a0, a1, ra, b0, b1, rb)
    distance = p.distance
    if not math.isfinite(float(distance.sum())):  # a NaN or infinity anywhere lands here
        _raise_non_finite(a0, a1, ra, b0, b1, rb)
    if ra.shape[0] and (ra.min() < 0.0 or rb.min() < 0.0):
        raise InvalidInputError("capsule radii must be non-negative [m], got "
                                f"{min(ra.min(), rb.min())!r}")
    return Proximities(distance, p.point_a, p.point_b, p.normal)


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


#: Coal's GJK and EPA tolerances [m] of every distance measured with coal (here and in
#: the kernel's collision scene, ``kernel.CoalPairs``).
GJK_TOLERANCE = 1e-10
EPA_TOLERANCE = 1e-10

#: The request of every coal call here: GJK's and EPA's tolerances tightened to 1e-10.
#: Shared and never changed (a request is read-only to coal).
_REQUEST = coal.DistanceRequest()
_REQUEST.gjk_tolerance = GJK_TOLERANCE
_REQUEST.epa_tolerance = EPA_TOLERANCE


def coal_proximity(geom_a: Any, T_a: FloatArray, geom_b: Any, T_b: FloatArray) -> Proximity:
    """Signed distance, witness points and normal of two coal geometries.

    The same conventions as :func:`proximity` (which calls it for pairs with a box).
    The collision scene measures its pairs with a box by the same rules in the kernel,
    with coal's C++ library (``kernel.CoalPairs``).

    Parameters
    ----------
    geom_a, geom_b : coal.CollisionGeometry
        The geometries, in their own frames (:func:`coal_shape`).
    T_a, T_b : ndarray, shape (4, 4)
        Their poses in the world [m].
    """
    result = coal.DistanceResult()
    tf_a = coal.Transform3s(T_a[:3, :3], T_a[:3, 3])
    tf_b = coal.Transform3s(T_b[:3, :3], T_b[:3, 3])
    distance = float(coal.distance(geom_a, tf_a, geom_b, tf_b, _REQUEST, result))
    point_a = np.array(result.getNearestPoint1(), dtype=np.float64)
    point_b = np.array(result.getNearestPoint2(), dtype=np.float64)
    normal = np.array(result.normal, dtype=np.float64)
    length = math.sqrt(float(normal @ normal))  # NaN for a non-finite normal
    if not abs(length - 1.0) <= 1e-6:
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
    capsule is a coal sphere; a box is centred on its pose (:func:`coal_parts`).
    """
    kind, numbers, T = coal_parts(shape)
    if kind == COAL_BOX:
        return coal.Box(*numbers.tolist()), T
    if kind == COAL_SPHERE:
        return coal.Sphere(float(numbers[0])), T
    return coal.Capsule(float(numbers[0]), float(numbers[1])), T


#: The kinds of :func:`coal_parts` (``kernel.CoalPairs`` reads the same numbers).
COAL_BOX, COAL_CAPSULE, COAL_SPHERE = 1, 2, 3


def coal_parts(shape: Capsule | Box) -> tuple[int, FloatArray, FloatArray]:
    """Return the coal geometry of a shape as numbers: its kind, sizes and pose.

    Returns
    -------
    kind : int
        :data:`COAL_BOX`, :data:`COAL_CAPSULE` or :data:`COAL_SPHERE` (a zero-length
        capsule).
    numbers : ndarray, shape (3,)
        A box's side lengths [m]; a capsule's radius and length [m] (then 0); a
        sphere's radius [m] (then 0, 0).
    pose : ndarray, shape (4, 4)
        The geometry's pose in the shape's frame: a box's own pose; a capsule's centre,
        with its axis as the local z axis.
    """
    if isinstance(shape, Box):
        return COAL_BOX, np.array(shape.size, dtype=np.float64), np.array(shape.pose)
    axis = shape.b - shape.a
    length = float(np.linalg.norm(axis))
    T = np.eye(4)
    T[:3, 3] = (shape.a + shape.b) / 2.0
    if length == 0.0:
        return COAL_SPHERE, np.array([shape.radius, 0.0, 0.0]), T
    T[:3, :3] = _frame_with_z(axis / length)
    return COAL_CAPSULE, np.array([shape.radius, length, 0.0]), T


def _frame_with_z(z: FloatArray) -> FloatArray:
    """Return a rotation matrix whose third column is the unit vector ``z``.

    Its first column is ``z`` crossed with the coordinate axis ``z`` is least aligned
    with, normalised (a capsule is the same about its axis: any such frame will do).
    """
    helper = np.zeros(3)
    helper[int(np.argmin(np.abs(z)))] = 1.0
    x = np.cross(z, helper)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])
