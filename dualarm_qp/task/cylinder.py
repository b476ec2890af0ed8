"""A generator line of a circular cylinder as the sliding path (:class:`CylinderSurface`)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._validate import as_array
from ..errors import InvalidInputError
from .surface_base import GraspSurface, SlideJoint, as_sigma, frame_from

FloatArray = NDArray[np.float64]


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
        rho = as_sigma(radius, "radius")
        if rho <= 0.0:
            raise InvalidInputError(f"radius must be > 0 m, got {rho:g}")
        theta = as_sigma(azimuth, "azimuth")
        self.radius = rho
        self.azimuth = theta
        a = np.array([math.cos(theta), math.sin(theta), 0.0])
        self._foot = rho * a
        self._R = frame_from(np.array([0.0, 0.0, 1.0]), a)
        self._R.setflags(write=False)
        lo, hi = as_sigma(sigma_min, "sigma_min"), as_sigma(sigma_max, "sigma_max")
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
        p[2] = as_sigma(sigma)
        return p

    def frame(self, sigma: float) -> FloatArray:
        """Constant ``[s*, n*, a*]`` along the generator."""
        as_sigma(sigma)
        return self._R.copy()

    def angular_rate(self, sigma: float) -> FloatArray:
        """Zero: the normal does not change along a generator."""
        as_sigma(sigma)
        return np.zeros(3)

    def sigma_of(self, r: Any) -> float:
        """``z`` of ``r`` [m]."""
        return float(as_array(r, "r", (3,))[2])

    def slide_joint(self) -> SlideJoint:
        """Return a prismatic joint along the generator (the x axis of ``R2``)."""
        return SlideJoint("prismatic", "x", self.pose(0.0), np.eye(4), 1.0)


__all__ = ["CylinderSurface"]
