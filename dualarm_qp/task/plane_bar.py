"""A straight sliding path on a plane (:class:`PlaneBar`): the paper's Fig. 4 bar."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._validate import as_array, check_limits
from ..errors import InvalidInputError, LimitsError
from .surface_base import GraspSurface, SlideJoint, as_bound, as_sigma, frame_from

FloatArray = NDArray[np.float64]


def unit_vector(value: Any, name: str) -> FloatArray:
    """Return a finite (3,) vector scaled to unit length."""
    v = as_array(value, name, (3,))
    norm = float(np.linalg.norm(v))
    if norm < 1e-12:
        raise InvalidInputError(f"{name} must be a non-zero vector, got {v}")
    return v / norm


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
        s = unit_vector(sliding, "sliding")
        a = unit_vector(normal, "normal")
        if abs(float(s @ a)) > 1e-9:
            raise InvalidInputError(
                f"sliding {s} must be orthogonal to normal {a} (s.a = {float(s @ a):.3g})"
            )
        lo_box, hi_box = as_bound(r_min, "r_min"), as_bound(r_max, "r_max")
        check_limits(lo_box, hi_box, "surface box r_min/r_max")
        lo, hi = line_box_range(o, s, lo_box, hi_box)
        lo = lo if sigma_min is None else as_sigma(sigma_min, "sigma_min")
        hi = hi if sigma_max is None else as_sigma(sigma_max, "sigma_max")
        if not (math.isfinite(lo) and math.isfinite(hi)):
            raise LimitsError(
                "the sliding line is unbounded inside the box r_min/r_max; "
                "give finite box bounds along it or sigma_min/sigma_max"
            )
        super().__init__(sigma_min=lo, sigma_max=hi, r_min=lo_box, r_max=hi_box)
        self.origin = o
        self._s = s
        self._a = a
        self._R = frame_from(s, a)
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
        return self.origin + as_sigma(sigma) * self._s

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
        as_sigma(sigma)
        return self._R.copy()

    def tangent(self, sigma: float) -> FloatArray:
        """Constant ``s*``."""
        as_sigma(sigma)
        return self._s.copy()

    def angular_rate(self, sigma: float) -> FloatArray:
        """Zero: a straight path on a plane does not turn the hand."""
        as_sigma(sigma)
        return np.zeros(3)

    def sigma_of(self, r: Any) -> float:
        """``s* . (r - origin)`` [m], the foot of the perpendicular from ``r``."""
        return float(self._s @ (as_array(r, "r", (3,)) - self.origin))

    def slide_joint(self) -> SlideJoint:
        """Return a prismatic joint along ``s*`` (the x axis of ``R2``) at ``origin``."""
        return SlideJoint("prismatic", "x", self.pose(0.0), np.eye(4), 1.0)


def line_box_range(
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


__all__ = ["PlaneBar", "line_box_range", "unit_vector"]
