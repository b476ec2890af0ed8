"""Capsules that contain given geometry: point sets, coal shapes and meshes.

:func:`fit_capsule` returns a capsule that contains every given ball (a point is a ball
of radius zero); :func:`geometry_balls` turns one coal collision geometry (a mesh, a
convex hull or a primitive) into balls whose convex hull contains it, so that a capsule
containing the balls contains the geometry. The capsules of a robot's links are built
on these (:mod:`dualarm_qp.geometry.links`).

The fit, for points ``c_i`` with radii ``r_i`` [m]:

1. the axis direction: of the three principal axes of the points (PCA), the one giving
   the smallest capsule;
2. for an axis line ``o + h u``, the tightest capsule along it: radius
   ``rho = max_i (p_i + r_i)`` with ``p_i`` the distance of ``c_i`` from the line, and
   endpoints at ``h_hi = max_i (h_i - sqrt((rho - r_i)^2 - p_i^2))`` and
   ``h_lo = min_i (h_i + sqrt(...))`` (the extreme projections ``h_i`` shrunk so that each
   ball just fits in the end caps); if ``h_lo > h_hi`` the segment shrinks to their
   midpoint;
3. the line (two tilt angles, two offsets) refined by Nelder-Mead on the capsule's
   volume, starting from step 1;
4. the radius recomputed as the largest ``distance(c_i, segment) + r_i``, plus
   :data:`FIT_MARGIN`, so the capsule contains every ball whatever the refinement did.
"""

from __future__ import annotations

import math
from typing import Any

import coal  # type: ignore[import-untyped]
import numpy as np
from numpy.typing import NDArray

from .._validate import as_array
from ..errors import InvalidInputError, ShapeError
from .shapes import Capsule

FloatArray = NDArray[np.float64]

#: Added to a fitted capsule's radius [m], so that every ball stays inside after the
#: rounding of later transforms.
FIT_MARGIN = 1e-9
#: Sides of the regular polygons that stand for the rim circles of cylinders and cones:
#: the polygons are circumscribed (vertices at ``R / cos(pi / N)``), so they contain
#: the circles; the radius grows by 0.5 % at N = 32.
CIRCLE_SIDES = 32


def fit_capsule(points: Any, radii: Any = None) -> Capsule:
    """Fit a small capsule that contains every ball ``(points[i], radii[i])``.

    Parameters
    ----------
    points : array_like, shape (m, 3)
        Ball centres (e.g. mesh vertices) in one frame [m], at least one.
    radii : array_like, shape (m,), optional
        Ball radii [m], non-negative; zero (bare points) by default.

    Returns
    -------
    Capsule
        In the frame of ``points``; ``distance(c_i, axis) + r_i <= radius`` for every
        ball (see the module docstring for the construction).

    Raises
    ------
    ShapeError, NonFiniteError, InvalidInputError
        Malformed points or radii, no point, or a negative radius.
    """
    c = as_array(points, "points", (-1, 3))
    if c.shape[0] == 0:
        raise InvalidInputError("a capsule needs at least one point to contain")
    r = np.zeros(c.shape[0]) if radii is None else as_array(radii, "radii", (c.shape[0],))
    if (r < 0.0).any():
        raise InvalidInputError("ball radii must be non-negative [m]")
    centroid = c.mean(axis=0)
    spread = c - centroid
    _, vecs = np.linalg.eigh(spread.T @ spread)
    best = min((_line_capsule(c, r, centroid, vecs[:, j]) for j in range(3)),
               key=lambda cap: cap[3])
    u0 = (best[1] - best[0])
    basis = _basis(u0 / np.linalg.norm(u0) if np.linalg.norm(u0) > 0 else vecs[:, 2])

    def volume(x: FloatArray) -> float:
        u = basis[2] + x[0] * basis[0] + x[1] * basis[1]
        o = centroid + x[2] * basis[0] + x[3] * basis[1]
        return _line_capsule(c, r, o, u / np.linalg.norm(u))[3]

    scale = float(np.sqrt((spread * spread).sum(axis=1).max())) or 1.0
    simplex = np.vstack([np.zeros(4), np.diag([0.1, 0.1, 0.1 * scale, 0.1 * scale])])
    from scipy.optimize import minimize  # on first fit: SciPy's optimiser is slow to import

    res = minimize(volume, np.zeros(4), method="Nelder-Mead",
                   options={"initial_simplex": simplex, "xatol": 1e-7 * scale,
                            "fatol": 1e-12, "maxiter": 800})
    if res.fun < best[3]:
        x = res.x
        u = basis[2] + x[0] * basis[0] + x[1] * basis[1]
        best = _line_capsule(c, r, centroid + x[2] * basis[0] + x[3] * basis[1],
                             u / np.linalg.norm(u))
    a, b = best[0], best[1]
    radius = float((_segment_distances(c, a, b) + r).max()) + FIT_MARGIN
    return Capsule(a, b, radius)


def _line_capsule(c: FloatArray, r: FloatArray, o: FloatArray,
                  u: FloatArray) -> tuple[FloatArray, FloatArray, float, float]:
    """Tightest capsule along the line ``o + h u`` (``u`` unit): ``(a, b, radius, volume)``."""
    rel = c - o
    h = rel @ u
    p = np.sqrt(np.maximum((rel * rel).sum(axis=1) - h * h, 0.0))
    rho = float((p + r).max())
    slack = np.sqrt(np.maximum((rho - r) ** 2 - p * p, 0.0))
    hi, lo = float((h - slack).max()), float((h + slack).min())
    if lo > hi:
        lo = hi = (lo + hi) / 2.0
    a, b = o + lo * u, o + hi * u
    radius = float((_segment_distances(c, a, b) + r).max())
    volume = math.pi * radius**2 * (hi - lo) + 4.0 / 3.0 * math.pi * radius**3
    return a, b, radius, volume


def _segment_distances(c: FloatArray, a: FloatArray, b: FloatArray) -> FloatArray:
    """Distances of the points ``c`` (m, 3) from the segment ``[a, b]`` [m]."""
    d = b - a
    dd = float(d @ d)
    t = np.zeros(c.shape[0]) if dd == 0.0 else np.clip((c - a) @ d / dd, 0.0, 1.0)
    gap = c - (a + t[:, None] * d)
    out: FloatArray = np.sqrt((gap * gap).sum(axis=1))
    return out


def _basis(z: FloatArray) -> FloatArray:
    """Rows ``x, y, z``: an orthonormal basis whose third vector is the unit ``z``."""
    helper = np.zeros(3)
    helper[int(np.argmin(np.abs(z)))] = 1.0
    x = np.cross(z, helper)
    x /= np.linalg.norm(x)
    return np.array([x, np.cross(z, x), z])


# ---------------------------------------------------------------- coal geometry
def geometry_balls(geometry: Any, pose: Any = None) -> tuple[FloatArray, FloatArray]:
    """Balls whose convex hull contains a coal collision geometry.

    Parameters
    ----------
    geometry : coal.CollisionGeometry
        A triangle mesh (``BVHModel*``: its vertices, with the file's scale already
        applied by the loader), a convex hull (``Convex``), or a primitive: ``Box``
        (its 8 corners), ``Sphere`` (itself), ``Capsule`` (its two end spheres),
        ``Cylinder`` and ``Cone`` (circumscribed :data:`CIRCLE_SIDES`-gons for their
        rims, and the apex), ``Ellipsoid`` (the corners of its bounding box). A
        primitive's swept-sphere radius is added to its balls.
    pose : array_like, shape (4, 4), optional
        Pose of the geometry in the frame the balls are wanted in [m]; identity by
        default.

    Returns
    -------
    centres : ndarray, shape (m, 3)
        Ball centres in that frame [m].
    radii : ndarray, shape (m,)
        Ball radii [m].

    Raises
    ------
    InvalidInputError
        A geometry without a bounded convex cover (a half-space, a plane, an octree,
        a height field) or of an unknown kind.
    """
    T = np.eye(4) if pose is None else as_array(pose, "pose", (4, 4))
    centres, radii = _local_balls(geometry)
    return centres @ T[:3, :3].T + T[:3, 3], radii


def _local_balls(g: Any) -> tuple[FloatArray, FloatArray]:
    """Balls of :func:`geometry_balls` in the geometry's own frame."""
    if isinstance(g, coal.BVHModelBase):
        v = np.array(g.vertices(), dtype=np.float64).reshape(-1, 3)
        if v.shape[0] == 0:
            raise InvalidInputError("a collision mesh has no vertices")
        return v, np.zeros(v.shape[0])
    if not isinstance(g, coal.ShapeBase):
        raise InvalidInputError(f"cannot bound a collision geometry of type "
                                f"{type(g).__name__} (meshes and shapes only)")
    swept = float(g.getSweptSphereRadius())
    n = CIRCLE_SIDES
    angles = 2.0 * np.pi * np.arange(n) / n
    if isinstance(g, coal.ConvexBase):
        pts = np.array(g.points(), dtype=np.float64).reshape(-1, 3)
    elif isinstance(g, coal.Box | coal.Ellipsoid):
        half = np.array(g.halfSide if isinstance(g, coal.Box) else g.radii, dtype=np.float64)
        signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
        pts = signs * half
    elif isinstance(g, coal.Sphere):
        return np.zeros((1, 3)), np.array([float(g.radius) + swept])
    elif isinstance(g, coal.Capsule):
        h = float(g.halfLength)
        return np.array([[0.0, 0.0, -h], [0.0, 0.0, h]]), np.full(2, float(g.radius) + swept)
    elif isinstance(g, coal.Cylinder | coal.Cone):
        rim = float(g.radius) / math.cos(math.pi / n)
        h = float(g.halfLength)
        ring = np.column_stack([rim * np.cos(angles), rim * np.sin(angles), np.full(n, -h)])
        top = (ring + np.array([0.0, 0.0, 2.0 * h]) if isinstance(g, coal.Cylinder)
               else np.array([[0.0, 0.0, h]]))
        pts = np.vstack([ring, top])
    else:
        raise InvalidInputError(f"cannot bound a collision shape of type {type(g).__name__} "
                                "(mesh, convex, box, sphere, capsule, cylinder, cone, "
                                "ellipsoid)")
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise ShapeError("shape points", (-1, 3), pts.shape)
    return pts, np.full(pts.shape[0], swept)
