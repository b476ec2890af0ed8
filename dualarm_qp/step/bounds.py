"""Rate bounds and range centres of one step (Eqs. 30-36 and 38-40).

Every variable of the step (a joint of either arm, a sliding grasp) gets a hard box on
its rate from its position range over one sample and its speed limit, and a centre: the
middle of the position-derived rate range, which the cost (Eq. 37) pulls it towards. A
variable that starts outside its range may never move further out.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


def rate_bounds(
    x: FloatArray,
    x_min: FloatArray,
    x_max: FloatArray,
    v_max: FloatArray,
    dt: float,
    recovery_fraction: float,
) -> tuple[FloatArray, FloatArray, FloatArray, NDArray[np.bool_]]:
    """Rate bounds from a position box and a speed limit (Eqs. 34-36 and Sec. 4).

    Parameters
    ----------
    x, x_min, x_max : ndarray
        Current positions and their box.
    v_max : ndarray
        Symmetric speed limits (``inf`` for none).
    dt : float
        Sampling interval [s].
    recovery_fraction : float
        See :class:`StepOptions`.

    Returns
    -------
    lower, upper : ndarray
        Hard bounds on the rate.
    center : ndarray
        Centre of the position-derived rate range (Eq. 39); 0 where the range is
        unbounded.
    recovering : ndarray of bool
        Positions outside their box.
    """
    with np.errstate(invalid="ignore"):
        lo = (np.asarray(x_min, dtype=np.float64) - x) / dt
        hi = (np.asarray(x_max, dtype=np.float64) - x) / dt
    return clip_rates(lo, hi, np.broadcast_to(np.asarray(v_max, dtype=np.float64), lo.shape),
                      recovery_fraction)


def clip_rates(lo: FloatArray, hi: FloatArray, v_max: FloatArray, recovery_fraction: float
               ) -> tuple[FloatArray, FloatArray, FloatArray, NDArray[np.bool_]]:
    """:func:`rate_bounds` from the position-derived rate range ``[lo, hi]``."""
    bounded = np.isfinite(lo) & np.isfinite(hi)
    center = np.where(bounded, 0.5 * (np.where(bounded, lo, 0.0) + np.where(bounded, hi, 0.0)),
                      0.0)
    # Below the box: may not move further down; with a recovery fraction it must
    # move up at least at that share of its speed limit. Above the box: mirrored.
    rec = recovery_fraction * v_max if recovery_fraction > 0.0 else np.zeros_like(v_max)
    below, above = lo > 0.0, hi < 0.0
    lower = np.where(below, np.minimum(lo, rec), np.maximum(lo, -v_max))
    upper = np.where(above, np.maximum(hi, -rec), np.minimum(hi, v_max))
    return lower, upper, center, below | above


def grasp_rate_range(
    surface_r: Sequence[float] | FloatArray,
    s_star: Sequence[float] | FloatArray,
    r_min: Sequence[float] | FloatArray,
    r_max: Sequence[float] | FloatArray,
    dt: float,
) -> tuple[float, float]:
    """``(rho_min, rho_max)`` of Eqs. 30-31 [m/s].

    Components with ``s*_i == 0`` do not move along axis i and are skipped. The
    arguments are 3-vectors (arrays or lists of floats).
    """
    rho_min, rho_max = -math.inf, math.inf
    for i in range(3):
        si = float(s_star[i])
        if abs(si) < 1e-12:
            continue
        a = (float(r_min[i]) - float(surface_r[i])) / (si * dt)
        b = (float(r_max[i]) - float(surface_r[i])) / (si * dt)
        rho_min = max(rho_min, min(a, b))
        rho_max = min(rho_max, max(a, b))
    return rho_min, rho_max


__all__ = ["clip_rates", "grasp_rate_range", "rate_bounds"]
