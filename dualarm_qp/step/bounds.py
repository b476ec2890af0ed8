"""The rate range of a sliding grasp over one sample (Eqs. 30-31).

Every variable of the step (a joint of either arm, a sliding grasp) gets the rates that
reach the ends of its position range in one sample (the step's context); for a grasp
the range is also the surface box ``[r_min, r_max]`` of the hand's point, which
:func:`grasp_rate_range` turns into rates. The range limits
(:mod:`~dualarm_qp.step.limits.ranges`, Eqs. 34-36 with recovery) and the centring cost
(:mod:`~dualarm_qp.step.cost`, Eqs. 38-40) read those rates.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from .._compiled import kernel
from ..errors import InvalidInputError

if TYPE_CHECKING:
    from ..task.surfaces import GraspSurface

FloatArray = NDArray[np.float64]


def grasp_rate_range(
    surface_r: Sequence[float] | FloatArray,
    s_star: Sequence[float] | FloatArray,
    r_min: Sequence[float] | FloatArray,
    r_max: Sequence[float] | FloatArray,
    dt: float,
) -> tuple[float, float]:
    """``(rho_min, rho_max)`` of Eqs. 30-31 [m/s].

    Components with ``s*_i == 0`` (below 1e-12) do not move along axis i and are
    skipped. The arguments are 3-vectors of numbers (``r_min`` and ``r_max`` may hold
    infinities) and ``dt > 0`` [s]. Computed by the kernel (``src/kernel/boxes.cpp``),
    which the step's grasp rates use.

    Raises
    ------
    InvalidInputError
        An argument is not a 3-vector of numbers, or ``dt`` is not a positive number.
    """
    rates = kernel.grasp_rate_range(_vector(surface_r, "r"), _vector(s_star, "s_star"),
                                    _vector(r_min, "r_min"), _vector(r_max, "r_max"),
                                    _step(dt))
    return rates.lower, rates.upper


def grasp_rates(surface: GraspSurface, sigma: float, dt: float) -> tuple[float, float]:
    """Return a grasp's rates to the ends of its range over one sample [m/s].

    Eqs. 30-31 at the surface's point and tangent at ``sigma`` (the surface checks
    ``sigma``), cut by the rates that reach ``sigma_min`` and ``sigma_max`` in one
    sample. Computed by the kernel, as the step computes the rates of a straight grasp
    (:attr:`~dualarm_qp.task.surfaces.GraspSurface.line`) itself.

    Raises
    ------
    InvalidInputError
        The surface's point or tangent is not a 3-vector of numbers, or ``dt`` is not a
        positive number.
    """
    point = _vector(surface.point(sigma), "the surface's point")
    tangent = _vector(surface.tangent(sigma), "the surface's tangent")
    rates = kernel.grasp_rates(point, tangent, float(sigma), surface.r_min, surface.r_max,
                               surface.sigma_min, surface.sigma_max, _step(dt))
    return rates.lower, rates.upper


def _vector(v: Sequence[float] | FloatArray, name: str) -> FloatArray:
    """Return ``v`` as a float64 3-vector, or raise InvalidInputError naming it."""
    raw = np.asarray(v)
    if raw.shape != (3,) or raw.dtype.kind not in "iuf":
        raise InvalidInputError(f"{name} must be a 3-vector of numbers, got {v!r}")
    return raw.astype(np.float64, copy=False)


def _step(dt: float) -> float:
    """Return ``dt`` as a positive float [s], or raise InvalidInputError."""
    try:
        value = float(dt)
    except (TypeError, ValueError, OverflowError):
        value = math.nan
    if not (value > 0.0 and math.isfinite(value)):
        raise InvalidInputError(f"dt must be a positive number of seconds, got {dt!r}")
    return value


__all__ = ["grasp_rate_range", "grasp_rates"]
