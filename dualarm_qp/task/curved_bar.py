"""A bar bent into a circular arc (:class:`CurvedBar`), where the sliding direction turns."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._validate import as_array
from ..errors import InvalidInputError, LimitsError
from .surface_base import GraspSurface, SlideJoint, as_sigma

FloatArray = NDArray[np.float64]


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
        rc = as_sigma(radius, "radius")
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
        lo, hi = as_sigma(sigma_min, "sigma_min"), as_sigma(sigma_max, "sigma_max")
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
        return self._point(as_sigma(sigma))

    def frame(self, sigma: float) -> FloatArray:
        """Frame ``[s*, n*, a*]`` with angle ``k sigma`` (see the class docstring)."""
        th = self._k * as_sigma(sigma)
        c, s = math.cos(th), math.sin(th)
        return np.array([[-s, 0.0, c], [0.0, -1.0, 0.0], [c, 0.0, s]])

    def tangent(self, sigma: float) -> FloatArray:
        """``s* = [-sin(k sigma), 0, cos(k sigma)]``."""
        th = self._k * as_sigma(sigma)
        return np.array([-math.sin(th), 0.0, math.cos(th)])

    def angular_rate(self, sigma: float) -> FloatArray:
        """Constant ``[0, -k, 0]`` [rad/m]."""
        as_sigma(sigma)
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


__all__ = ["CurvedBar"]
