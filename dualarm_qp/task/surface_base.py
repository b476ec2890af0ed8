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

This module holds the base class (:class:`GraspSurface`) and the sliding path as one
joint (:class:`SlideJoint`). Concrete paths, one module each: :class:`~.plane_bar.PlaneBar`
(the paper's Fig. 4 bar, and any straight path on a plane),
:class:`~.cylinder.CylinderSurface` (a generator line of a circular cylinder) and
:class:`~.curved_bar.CurvedBar` (a bar bent into a circular arc, where ``s*`` really
changes); :func:`~.case1.case1_pose` is the paper's Case 1 construction (Steps 1-4).
:mod:`.surfaces` imports them all.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._validate import as_number, check_limits
from ..errors import InvalidInputError, LimitsError, NonFiniteError, ShapeError

FloatArray = NDArray[np.float64]


def as_sigma(sigma: Any, name: str = "sigma") -> float:
    """Return ``sigma`` as a finite Python float [m]."""
    return as_number(sigma, name)


def as_bound(value: Any, name: str) -> FloatArray:
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


def frame_from(s: FloatArray, a: FloatArray) -> FloatArray:
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
        self.sigma_min = as_sigma(sigma_min, "sigma_min")
        self.sigma_max = as_sigma(sigma_max, "sigma_max")
        if self.sigma_min > self.sigma_max:
            raise LimitsError(
                f"sigma_min {self.sigma_min:g} m exceeds sigma_max {self.sigma_max:g} m"
            )
        self.r_min = as_bound(r_min, "r_min")
        self.r_max = as_bound(r_max, "r_max")
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
        s = as_sigma(sigma)
        return self.sigma_min - tol <= s <= self.sigma_max + tol

    def clamp(self, sigma: float) -> float:
        """``sigma`` clipped to the grasp range [m]."""
        return min(max(as_sigma(sigma), self.sigma_min), self.sigma_max)

    def __repr__(self) -> str:
        return f"{type(self).__name__}(sigma in [{self.sigma_min:g}, {self.sigma_max:g}] m)"


__all__ = ["GraspSurface", "SlideJoint", "as_bound", "as_sigma", "frame_from"]
