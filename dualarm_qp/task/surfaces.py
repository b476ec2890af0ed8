"""Object surfaces and the follower's sliding grasp path (paper Section 2, Eqs. 3-6, 16, 21).

The follower's hand touches the object on the surface ``phi(r) = 0`` (Eq. 3, object
coordinates) and slides along a one-dimensional path on it. The path is parametrised by
a scalar ``sigma`` [m], the arc length along the sliding direction, so that

* ``point(sigma)`` is the contact point ``r2`` in object coordinates [m],
* ``tangent(sigma) = d point / d sigma`` is the unit sliding vector ``s*`` (Eq. 4),
* ``frame(sigma) = R2 = [s*, n*, a*]`` (Eqs. 16 and 21) with ``a* = grad phi / |grad phi|``
  (Eq. 5) and ``n* = a* x s*`` (Eq. 6), a proper rotation from the follower-hand frame to
  the object frame,
* ``angular_rate(sigma) = kappa`` with ``dR2/dsigma = skew(kappa) @ R2`` [rad/m], in
  object coordinates. While the hand slides at speed ``m = d sigma/dt`` [m/s] the hand
  frame turns at ``kappa * m`` [rad/s] relative to the object.

All methods accept any finite ``sigma``, also outside ``[sigma_min, sigma_max]``: the
geometry is extended naturally (a line, a generator line, a circle) so that a state that
starts outside the grasp range (as in the paper's Table 2, ``r2_z = 450 mm`` against
``r_max = 400 mm``) can still be evaluated; the range is a bound for the solvers, not a
domain restriction.

Concrete paths: :class:`PlaneBar` (the paper's Fig. 4 bar, and any straight path on a
plane), :class:`CylinderSurface` (a generator line of a circular cylinder) and
:class:`CurvedBar` (a bar bent into a circular arc, where ``s*`` really changes).
:func:`case1_pose` is the paper's Case 1 construction (Steps 1-4) from a surface and a
centre line ``x(z), y(z)``.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._validate import as_array, as_number, check_limits
from ..errors import InvalidInputError, LimitsError, NonFiniteError, ShapeError

FloatArray = NDArray[np.float64]

__all__ = [
    "GraspSurface",
    "SlideJoint",
    "PlaneBar",
    "CylinderSurface",
    "CurvedBar",
    "CenterLine",
    "case1_pose",
]


def _as_sigma(sigma: Any, name: str = "sigma") -> float:
    """Return ``sigma`` as a finite Python float [m]."""
    return as_number(sigma, name)


def _as_bound(value: Any, name: str) -> FloatArray:
    """Return a (3,) box bound [m]; +-inf allowed, NaN not."""
    try:
        arr = np.array(value, dtype=np.float64)
    except (TypeError, ValueError, OverflowError) as err:
        raise InvalidInputError(f"{name} must be an array of numbers: {err}") from err
    if arr.shape != (3,):
        raise ShapeError(name, (3,), arr.shape)
    if np.any(np.isnan(arr)):
        raise NonFiniteError(name)
    return arr


def _unit(value: Any, name: str) -> FloatArray:
    """Return a finite (3,) vector scaled to unit length."""
    v = as_array(value, name, (3,))
    norm = float(np.linalg.norm(v))
    if norm < 1e-12:
        raise InvalidInputError(f"{name} must be a non-zero vector, got {v}")
    return v / norm


def _frame_from(s: FloatArray, a: FloatArray) -> FloatArray:
    """Rotation ``[s*, n*, a*]`` with ``n* = a* x s*`` (Eq. 6); needs unit ``s`` ⟂ ``a``."""
    R = np.empty((3, 3))
    R[:, 0] = s
    R[:, 1] = np.cross(a, s)
    R[:, 2] = a
    return R


@dataclass(frozen=True)
class SlideJoint:
    """The sliding path as one joint: ``H2(sigma) = P @ M(rate * sigma) @ C``.

    ``M(theta)`` is the motion of a one-dof joint about or along the x or y axis of its
    own frame: a translation by ``theta`` [m] (``kind="prismatic"``) or a rotation by
    ``theta`` [rad] (``kind="revolute"``). A straight path is a prismatic joint, a
    circular arc a revolute joint about its centre of curvature.

    Attributes
    ----------
    kind : {"prismatic", "revolute"}
        Joint type.
    axis : {"x", "y"}
        Joint axis in the joint frame.
    placement : ndarray, shape (4, 4)
        ``P``: the joint frame in object coordinates [m].
    child : ndarray, shape (4, 4)
        ``C``: the hand frame in the moving joint frame [m].
    rate : float
        ``d theta / d sigma``: 1 for a prismatic joint, the signed curvature [rad/m]
        for a revolute one.
    """

    kind: str
    axis: str
    placement: FloatArray
    child: FloatArray
    rate: float


class GraspSurface(ABC):
    """A surface ``phi(r) = 0`` and a sliding path on it, in object coordinates.

    Subclasses implement the geometry; this base class stores the bounds and provides
    :meth:`tangent`, :meth:`normal`, :meth:`pose`, :meth:`contains` and :meth:`clamp`.

    Parameters
    ----------
    sigma_min, sigma_max : float
        Grasp range of the path parameter [m] (finite, ``sigma_min <= sigma_max``).
    r_min, r_max : array_like, shape (3,)
        The paper's positional box of Eq. 3 [m], object coordinates; components may be
        ``-inf`` / ``+inf``.

    Attributes
    ----------
    sigma_min, sigma_max : float
        Grasp range [m].
    r_min, r_max : ndarray, shape (3,)
        Box of Eq. 3 [m].
    """

    def __init__(self, *, sigma_min: float, sigma_max: float, r_min: Any, r_max: Any) -> None:
        self.sigma_min = _as_sigma(sigma_min, "sigma_min")
        self.sigma_max = _as_sigma(sigma_max, "sigma_max")
        if self.sigma_min > self.sigma_max:
            raise LimitsError(
                f"sigma_min {self.sigma_min:g} m exceeds sigma_max {self.sigma_max:g} m"
            )
        self.r_min = _as_bound(r_min, "r_min")
        self.r_max = _as_bound(r_max, "r_max")
        check_limits(self.r_min, self.r_max, "surface box r_min/r_max")

    # --- geometry every subclass provides -------------------------------------------
    @abstractmethod
    def phi(self, r: Any) -> float:
        """Implicit surface function of Eq. 3 at ``r`` (object coordinates) [m]."""

    @abstractmethod
    def grad_phi(self, r: Any) -> FloatArray:
        """Gradient of :meth:`phi` at ``r`` (object coordinates), shape (3,)."""

    @abstractmethod
    def point(self, sigma: float) -> FloatArray:
        """Contact point ``r2(sigma)`` in object coordinates [m], shape (3,)."""

    @abstractmethod
    def frame(self, sigma: float) -> FloatArray:
        """Hand orientation ``R2(sigma) = [s*, n*, a*]`` (object <- hand), shape (3, 3)."""

    @abstractmethod
    def angular_rate(self, sigma: float) -> FloatArray:
        """``kappa`` [rad/m] with ``dR2/dsigma = skew(kappa) @ R2``, object coordinates."""

    @abstractmethod
    def sigma_of(self, r: Any) -> float:
        """Path parameter [m] of the path point nearest to ``r`` (object coordinates).

        Exact inverse of :meth:`point` on the path: ``sigma_of(point(s)) == s``. The
        result is not clipped to the grasp range.
        """

    @abstractmethod
    def slide_joint(self) -> SlideJoint:
        """Return the sliding path as one joint (see :class:`SlideJoint`)."""

    # --- shared helpers --------------------------------------------------------------
    def points(self, sigmas: FloatArray) -> FloatArray:
        """Return :meth:`point` at each of ``sigmas`` (k,) [m], shape (k, 3).

        One call per value here; a straight path overrides it with one product.
        """
        return np.array([self.point(float(s)) for s in sigmas]).reshape(-1, 3)

    def tangents(self, sigmas: FloatArray) -> FloatArray:
        """Return :meth:`tangent` at each of ``sigmas`` (k,), shape (k, 3)."""
        return np.array([self.tangent(float(s)) for s in sigmas]).reshape(-1, 3)

    def tangent(self, sigma: float) -> FloatArray:
        """Return the unit sliding vector ``s* = d point / d sigma`` (Eq. 4), object coords."""
        return self.frame(sigma)[:, 0].copy()

    @property
    def line(self) -> tuple[FloatArray, FloatArray] | None:
        """A straight path's ``(origin, direction)`` (a :class:`PlaneBar`'s), or None.

        A straight path has ``point(sigma) = origin + sigma * direction`` (a product, then
        a sum, as numpy computes it) and the tangent ``direction``: when every sliding
        grasp has a line (and there is no Case 2 support), the step's kernel computes the
        grasps' rates itself from them (:class:`~dualarm_qp.step.build.StepBuilder`).
        None here: the surface's own :meth:`point` and :meth:`tangent` are read.
        """
        return None

    def normal(self, sigma: float) -> FloatArray:
        """Return the unit approach vector ``a* = grad phi / |grad phi|`` (Eq. 5), object coords."""
        return self.frame(sigma)[:, 2].copy()

    def pose(self, sigma: float) -> FloatArray:
        """Follower-hand pose in the object frame, ``H2(sigma)`` of Eq. 16, shape (4, 4)."""
        H = np.eye(4)
        H[:3, :3] = self.frame(sigma)
        H[:3, 3] = self.point(sigma)
        return H

    @property
    def sigma_center(self) -> float:
        """Centre of the grasp range [m] (the ``rho_c`` of Eq. 40 for the grasp)."""
        return 0.5 * (self.sigma_min + self.sigma_max)

    def contains(self, sigma: float, *, tol: float = 0.0) -> bool:
        """Whether ``sigma`` lies in ``[sigma_min - tol, sigma_max + tol]``."""
        s = _as_sigma(sigma)
        return self.sigma_min - tol <= s <= self.sigma_max + tol

    def clamp(self, sigma: float) -> float:
        """``sigma`` clipped to the grasp range [m]."""
        return min(max(_as_sigma(sigma), self.sigma_min), self.sigma_max)

    def __repr__(self) -> str:
        return f"{type(self).__name__}(sigma in [{self.sigma_min:g}, {self.sigma_max:g}] m)"


class PlaneBar(GraspSurface):
    """A straight sliding path on a plane: the paper's Fig. 4 bar and its generalisations.

    The surface is the plane ``a* . (r - origin) = 0`` and the path the line
    ``point(sigma) = origin + sigma * s*``; the frame is constant (``kappa = 0``).
    With the defaults this is the paper's bar: surface ``x = 0``, sliding along ``+z``,
    ``a* = [1, 0, 0]``, ``s* = [0, 0, 1]``, ``n* = a* x s* = [0, -1, 0]``,
    ``sigma = z`` and the box ``r_min = [0, 0, 0]``, ``r_max = [0, 0, 0.4]`` m.

    Parameters
    ----------
    r_min, r_max : array_like, shape (3,), keyword-only
        Box of Eq. 3 [m] in object coordinates; +-inf allowed. Unless ``sigma_min`` /
        ``sigma_max`` are given, the grasp range is the part of the line inside the box.
    origin : array_like, shape (3,), keyword-only
        Point of the path with ``sigma = 0`` [m], object coordinates.
    sliding : array_like, shape (3,), keyword-only
        Sliding direction ``s*`` (normalised here).
    normal : array_like, shape (3,), keyword-only
        Surface normal ``a*`` (normalised here); must be orthogonal to ``sliding``.
    sigma_min, sigma_max : float or None, keyword-only
        Explicit grasp range [m]; overrides the range derived from the box.

    Raises
    ------
    InvalidInputError
        ``sliding`` and ``normal`` are zero or not orthogonal.
    LimitsError
        The line misses the box, or the range is unbounded and no explicit range is given.
    """

    def __init__(
        self,
        *,
        r_min: Any = (0.0, 0.0, 0.0),
        r_max: Any = (0.0, 0.0, 0.4),
        origin: Any = (0.0, 0.0, 0.0),
        sliding: Any = (0.0, 0.0, 1.0),
        normal: Any = (1.0, 0.0, 0.0),
        sigma_min: float | None = None,
        sigma_max: float | None = None,
    ) -> None:
        o = as_array(origin, "origin", (3,)).copy()
        s = _unit(sliding, "sliding")
        a = _unit(normal, "normal")
        if abs(float(s @ a)) > 1e-9:
            raise InvalidInputError(
                f"sliding {s} must be orthogonal to normal {a} (s.a = {float(s @ a):.3g})"
            )
        lo_box, hi_box = _as_bound(r_min, "r_min"), _as_bound(r_max, "r_max")
        check_limits(lo_box, hi_box, "surface box r_min/r_max")
        lo, hi = _line_box_range(o, s, lo_box, hi_box)
        lo = lo if sigma_min is None else _as_sigma(sigma_min, "sigma_min")
        hi = hi if sigma_max is None else _as_sigma(sigma_max, "sigma_max")
        if not (math.isfinite(lo) and math.isfinite(hi)):
            raise LimitsError(
                "the sliding line is unbounded inside the box r_min/r_max; "
                "give finite box bounds along it or sigma_min/sigma_max"
            )
        super().__init__(sigma_min=lo, sigma_max=hi, r_min=lo_box, r_max=hi_box)
        self.origin = o
        self._s = s
        self._a = a
        self._R = _frame_from(s, a)
        self._R.setflags(write=False)

    def phi(self, r: Any) -> float:
        """Signed distance ``a* . (r - origin)`` to the plane [m]."""
        return float(self._a @ (as_array(r, "r", (3,)) - self.origin))

    def grad_phi(self, r: Any) -> FloatArray:
        """Constant gradient ``a*``."""
        as_array(r, "r", (3,))
        return self._a.copy()

    def point(self, sigma: float) -> FloatArray:
        """``origin + sigma * s*`` [m]."""
        return self.origin + _as_sigma(sigma) * self._s

    @property
    def line(self) -> tuple[FloatArray, FloatArray] | None:
        """``(origin, s*)``: the path is straight (see :attr:`GraspSurface.line`).

        None for a subclass with a path of its own (one that overrides :meth:`point`
        or :meth:`tangent`): the kernel would not see it.
        """
        cls = type(self)
        if cls.point is not PlaneBar.point or cls.tangent is not PlaneBar.tangent:
            return None
        return self.origin, self._s

    def points(self, sigmas: FloatArray) -> FloatArray:
        """Return :meth:`point` at each of ``sigmas`` (k,), in one product [m], shape (k, 3)."""
        return self.origin + np.asarray(sigmas, dtype=np.float64)[:, None] * self._s

    def tangents(self, sigmas: FloatArray) -> FloatArray:
        """Return the constant ``s*`` for each of ``sigmas`` (k,), shape (k, 3)."""
        return np.tile(self._s, (np.shape(sigmas)[0], 1))

    def frame(self, sigma: float) -> FloatArray:
        """Constant ``[s*, n*, a*]``."""
        _as_sigma(sigma)
        return self._R.copy()

    def tangent(self, sigma: float) -> FloatArray:
        """Constant ``s*``."""
        _as_sigma(sigma)
        return self._s.copy()

    def angular_rate(self, sigma: float) -> FloatArray:
        """Zero: a straight path on a plane does not turn the hand."""
        _as_sigma(sigma)
        return np.zeros(3)

    def sigma_of(self, r: Any) -> float:
        """``s* . (r - origin)`` [m], the foot of the perpendicular from ``r``."""
        return float(self._s @ (as_array(r, "r", (3,)) - self.origin))

    def slide_joint(self) -> SlideJoint:
        """Return a prismatic joint along ``s*`` (the x axis of ``R2``) at ``origin``."""
        return SlideJoint("prismatic", "x", self.pose(0.0), np.eye(4), 1.0)


def _line_box_range(
    o: FloatArray, s: FloatArray, lo: FloatArray, hi: FloatArray, tol: float = 1e-9
) -> tuple[float, float]:
    """Interval of ``sigma`` with ``lo <= o + sigma s <= hi`` (slab method)."""
    t_lo, t_hi = -math.inf, math.inf
    for i in range(3):
        if abs(s[i]) <= 1e-12:
            if not (lo[i] - tol <= o[i] <= hi[i] + tol):
                raise LimitsError(
                    f"the sliding line never enters the box: coordinate {i} is {o[i]:g} m, "
                    f"outside [{lo[i]:g}, {hi[i]:g}] m"
                )
            continue
        a, b = (lo[i] - o[i]) / s[i], (hi[i] - o[i]) / s[i]
        if a > b:
            a, b = b, a
        t_lo, t_hi = max(t_lo, a), min(t_hi, b)
    if t_lo > t_hi + tol:
        raise LimitsError("the sliding line never enters the box r_min/r_max")
    return t_lo, max(t_lo, t_hi)


class CylinderSurface(GraspSurface):
    """A circular cylinder of radius ``rho`` about the object z axis; slide along a generator.

    ``phi(r) = (x^2 + y^2 - rho^2) / (2 rho)`` (twice differentiable everywhere, unit
    gradient on the surface). The grasp slides along the generator line at azimuth
    ``theta``: ``point(sigma) = [rho cos theta, rho sin theta, sigma]``, ``s* = [0, 0, 1]``,
    ``a* = [cos theta, sin theta, 0]`` (outward radial normal),
    ``n* = a* x s* = [sin theta, -cos theta, 0]``. At ``theta = 0`` the frame equals
    the :class:`PlaneBar` frame.

    Parameters
    ----------
    radius : float
        Cylinder radius ``rho`` [m], > 0.
    azimuth : float, keyword-only
        Azimuth ``theta`` of the generator [rad] about the object z axis from +x.
    sigma_min, sigma_max : float, keyword-only
        Grasp range along the generator (``sigma = z``) [m].

    Notes
    -----
    ``r_min`` / ``r_max`` are the bounding box of the grasp segment.
    """

    def __init__(
        self,
        radius: float,
        *,
        azimuth: float = 0.0,
        sigma_min: float = 0.0,
        sigma_max: float = 0.4,
    ) -> None:
        rho = _as_sigma(radius, "radius")
        if rho <= 0.0:
            raise InvalidInputError(f"radius must be > 0 m, got {rho:g}")
        theta = _as_sigma(azimuth, "azimuth")
        self.radius = rho
        self.azimuth = theta
        a = np.array([math.cos(theta), math.sin(theta), 0.0])
        self._foot = rho * a
        self._R = _frame_from(np.array([0.0, 0.0, 1.0]), a)
        self._R.setflags(write=False)
        lo, hi = _as_sigma(sigma_min, "sigma_min"), _as_sigma(sigma_max, "sigma_max")
        p0, p1 = self._foot + np.array([0.0, 0.0, lo]), self._foot + np.array([0.0, 0.0, hi])
        super().__init__(
            sigma_min=lo, sigma_max=hi, r_min=np.minimum(p0, p1), r_max=np.maximum(p0, p1)
        )

    def phi(self, r: Any) -> float:
        """``(x^2 + y^2 - rho^2) / (2 rho)`` [m]."""
        v = as_array(r, "r", (3,))
        return float((v[0] ** 2 + v[1] ** 2 - self.radius**2) / (2.0 * self.radius))

    def grad_phi(self, r: Any) -> FloatArray:
        """``[x, y, 0] / rho``."""
        v = as_array(r, "r", (3,))
        return np.array([v[0], v[1], 0.0]) / self.radius

    def point(self, sigma: float) -> FloatArray:
        """``[rho cos theta, rho sin theta, sigma]`` [m]."""
        p = self._foot.copy()
        p[2] = _as_sigma(sigma)
        return p

    def frame(self, sigma: float) -> FloatArray:
        """Constant ``[s*, n*, a*]`` along the generator."""
        _as_sigma(sigma)
        return self._R.copy()

    def angular_rate(self, sigma: float) -> FloatArray:
        """Zero: the normal does not change along a generator."""
        _as_sigma(sigma)
        return np.zeros(3)

    def sigma_of(self, r: Any) -> float:
        """``z`` of ``r`` [m]."""
        return float(as_array(r, "r", (3,))[2])

    def slide_joint(self) -> SlideJoint:
        """Return a prismatic joint along the generator (the x axis of ``R2``)."""
        return SlideJoint("prismatic", "x", self.pose(0.0), np.eye(4), 1.0)


class CurvedBar(GraspSurface):
    """A bar bent into a circular arc of radius ``R_c`` in the object x-z plane.

    The grasped face is the cylinder of radius ``R_c`` whose axis is parallel to the
    object y axis through the centre of curvature ``c``. The path is chosen so that at
    ``sigma = 0`` it matches the :class:`PlaneBar` (``r2 = 0``, ``s* = +z``, ``a* = +x``).
    With the signed curvature ``k = +1/R_c`` (``side="outer"``: the hand is on the
    convex face, ``c = [-R_c, 0, 0]``) or ``k = -1/R_c`` (``side="inner"``: the concave
    face, ``c = [+R_c, 0, 0]``):

    * ``point(sigma) = [(cos(k sigma) - 1) / k, 0, sin(k sigma) / k]``
    * ``s* = [-sin(k sigma), 0, cos(k sigma)]``, ``a* = [cos(k sigma), 0, sin(k sigma)]``
      (pointing out of the bar material, away from ``c`` on the outer face, towards it
      on the inner face), ``n* = [0, -1, 0]``
    * ``R2(sigma) = rot_y(-k sigma) @ R2(0)``, so ``kappa = [0, -k, 0]`` [rad/m].

    Parameters
    ----------
    radius : float
        Radius of curvature ``R_c`` [m] of the grasped face, > 0.
    side : {"outer", "inner"}, keyword-only
        Which face of the bar the follower slides on.
    sigma_min, sigma_max : float, keyword-only
        Grasp range (arc length from the ``sigma = 0`` point) [m]; ``|sigma| / R_c``
        must stay below pi.

    Notes
    -----
    ``phi(r) = +-((x - c_x)^2 + z^2 - R_c^2) / (2 R_c)`` (sign ``+`` for the outer face);
    its gradient is unit on the surface and points along ``a*``. The grasp range is the
    arc ``[sigma_min, sigma_max]``; ``r_min`` / ``r_max`` are unbounded (no box of Eq. 3:
    that box describes a straight path).
    """

    SIDES = ("outer", "inner")

    def __init__(
        self,
        radius: float,
        *,
        side: str = "outer",
        sigma_min: float = 0.0,
        sigma_max: float = 0.4,
    ) -> None:
        rc = _as_sigma(radius, "radius")
        if rc <= 0.0:
            raise InvalidInputError(f"radius must be > 0 m, got {rc:g}")
        if side not in self.SIDES:
            raise InvalidInputError(f"unknown side {side!r} (valid: {', '.join(self.SIDES)})")
        eps = 1.0 if side == "outer" else -1.0
        self.radius = rc
        self.side = side
        self._eps = eps
        self._k = eps / rc
        self._cx = -eps * rc
        lo, hi = _as_sigma(sigma_min, "sigma_min"), _as_sigma(sigma_max, "sigma_max")
        if max(abs(lo), abs(hi)) / rc >= math.pi:
            raise LimitsError(
                f"the grasp arc must turn less than pi rad: |sigma| / R_c up to "
                f"{max(abs(lo), abs(hi)) / rc:.3g}"
            )
        if lo > hi:
            raise LimitsError(f"sigma_min {lo:g} m exceeds sigma_max {hi:g} m")
        # The grasp range is taken along the arc (sigma), not as a box in object
        # coordinates: Eqs. 30-31 assume a straight path, and on an arc the box of its
        # end points is empty along the tangent once the grasp is outside the range.
        inf = math.inf
        super().__init__(sigma_min=lo, sigma_max=hi, r_min=(-inf, -inf, -inf),
                         r_max=(inf, inf, inf))

    @property
    def curvature(self) -> float:
        """Signed curvature ``k`` [1/m] (positive on the outer face)."""
        return self._k

    @property
    def center(self) -> FloatArray:
        """Centre of curvature ``c`` [m], object coordinates."""
        return np.array([self._cx, 0.0, 0.0])

    def _point(self, sigma: float) -> FloatArray:
        th = self._k * sigma
        return np.array([(math.cos(th) - 1.0) / self._k, 0.0, math.sin(th) / self._k])

    def phi(self, r: Any) -> float:
        """``+-((x - c_x)^2 + z^2 - R_c^2) / (2 R_c)`` [m]."""
        v = as_array(r, "r", (3,))
        dx = v[0] - self._cx
        return float(self._eps * (dx * dx + v[2] ** 2 - self.radius**2) / (2.0 * self.radius))

    def grad_phi(self, r: Any) -> FloatArray:
        """``+-[x - c_x, 0, z] / R_c``."""
        v = as_array(r, "r", (3,))
        return (self._eps / self.radius) * np.array([v[0] - self._cx, 0.0, v[2]])

    def point(self, sigma: float) -> FloatArray:
        """``[(cos(k sigma) - 1) / k, 0, sin(k sigma) / k]`` [m]."""
        return self._point(_as_sigma(sigma))

    def frame(self, sigma: float) -> FloatArray:
        """Frame ``[s*, n*, a*]`` with angle ``k sigma`` (see the class docstring)."""
        th = self._k * _as_sigma(sigma)
        c, s = math.cos(th), math.sin(th)
        return np.array([[-s, 0.0, c], [0.0, -1.0, 0.0], [c, 0.0, s]])

    def tangent(self, sigma: float) -> FloatArray:
        """``s* = [-sin(k sigma), 0, cos(k sigma)]``."""
        th = self._k * _as_sigma(sigma)
        return np.array([-math.sin(th), 0.0, math.cos(th)])

    def angular_rate(self, sigma: float) -> FloatArray:
        """Constant ``[0, -k, 0]`` [rad/m]."""
        _as_sigma(sigma)
        return np.array([0.0, -self._k, 0.0])

    def sigma_of(self, r: Any) -> float:
        """Arc parameter of the radial projection of ``r`` onto the arc [m].

        Uses ``k sigma = atan2(k (z - c_z), k (x - c_x))``, in ``(-pi, pi]``.
        """
        v = as_array(r, "r", (3,))
        k = self._k
        return math.atan2(k * v[2], k * (v[0] - self._cx)) / k

    def slide_joint(self) -> SlideJoint:
        """Return a revolute joint about the object y axis through the centre of curvature.

        ``H2(sigma) = T(c) rot_y(-k sigma) T(-c) H2(0)``: joint angle ``-k sigma``.
        """
        P, C = np.eye(4), self.pose(0.0)
        P[0, 3] = self._cx
        C[0, 3] -= self._cx
        return SlideJoint("revolute", "y", P, C, -self._k)


@dataclass(frozen=True)
class CenterLine:
    """Centre line ``x = x(z), y = y(z)`` of the projected surface (paper Step 2).

    Attributes
    ----------
    x, y : callable float -> float
        Object-frame ``x`` and ``y`` [m] of the centre line at height ``z`` [m].
    dx_dz, dy_dz : callable float -> float
        Their derivatives ``alpha = dx/dz`` and ``beta = dy/dz`` (dimensionless).
    """

    x: Callable[[float], float]
    y: Callable[[float], float]
    dx_dz: Callable[[float], float]
    dy_dz: Callable[[float], float]


def case1_pose(
    phi: Callable[[FloatArray], float] | None,
    line: CenterLine,
    z: float,
    *,
    grad_phi: Callable[[FloatArray], Any] | None = None,
    fd_step: float = 1e-6,
) -> FloatArray:
    """Supporting pose ``H2(r*)`` of Case 1 (paper Steps 1-4, Eqs. 3-6 and 16).

    With ``r* = [x(z), y(z), z]`` (Step 2):

    * ``s* = [alpha, beta, 1] / sqrt(1 + alpha^2 + beta^2)`` (Eq. 4),
    * ``a* = grad phi(r*) / |grad phi(r*)|`` (Eq. 5),
    * ``n* = a* x s*`` (Eq. 6).

    The paper assumes ``s*`` is tangent to the surface. That holds when the centre
    line lies on the surface, but a centre line of a *projection* (Step 1) need not,
    and then ``s* . a* != 0`` and ``[s*, n*, a*]`` is not a rotation. We therefore
    project ``s*`` onto the tangent plane, ``s* <- (s* - (s*.a*) a*)``, and renormalise
    (a no-op when ``s*`` is already tangent). The result is always a proper rotation.

    Parameters
    ----------
    phi : callable or None
        Surface function ``phi(r)`` of Eq. 3 (object coordinates, [m]); used only to
        take a central-difference gradient when ``grad_phi`` is not given.
    line : CenterLine
        The centre line and its slopes.
    z : float
        Object-frame height ``r*_z`` [m] at which to evaluate.
    grad_phi : callable, optional, keyword-only
        Exact gradient of ``phi``; preferred over differencing.
    fd_step : float, keyword-only
        Step [m] of the central difference when ``grad_phi`` is None.

    Returns
    -------
    ndarray, shape (4, 4)
        ``H2 = [s*, n*, a*, r*; 0 0 0 1]``, the follower-hand pose in the object frame.

    Raises
    ------
    InvalidInputError
        Neither ``phi`` nor ``grad_phi`` given, ``grad phi(r*) = 0``, or the centre line
        is normal to the surface (no tangent direction left after projection).
    """
    zz = _as_sigma(z, "z")
    r = np.array([float(line.x(zz)), float(line.y(zz)), zz])
    alpha, beta = float(line.dx_dz(zz)), float(line.dy_dz(zz))
    if not (np.all(np.isfinite(r)) and math.isfinite(alpha) and math.isfinite(beta)):
        raise NonFiniteError("center line at z")
    if grad_phi is not None:
        g = as_array(grad_phi(r), "grad_phi(r*)", (3,))
    elif phi is not None:
        g = np.empty(3)
        for i in range(3):
            e = np.zeros(3)
            e[i] = fd_step
            g[i] = (float(phi(r + e)) - float(phi(r - e))) / (2.0 * fd_step)
    else:
        raise InvalidInputError("case1_pose needs phi or grad_phi")
    gn = float(np.linalg.norm(g))
    if gn < 1e-12:
        raise InvalidInputError(f"grad phi vanishes at r* = {r}: no surface normal (Eq. 5)")
    a = g / gn
    s = np.array([alpha, beta, 1.0]) / math.sqrt(1.0 + alpha * alpha + beta * beta)
    s = s - float(s @ a) * a
    sn = float(np.linalg.norm(s))
    if sn < 1e-9:
        raise InvalidInputError(
            f"the centre line is normal to the surface at r* = {r}: no sliding direction"
        )
    H = np.eye(4)
    H[:3, :3] = _frame_from(s / sn, a)
    H[:3, 3] = r
    return H
