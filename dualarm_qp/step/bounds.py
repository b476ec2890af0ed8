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

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


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
    # Python floats: for three numbers a list beats numpy's per-element indexing.
    for r, si, lo, hi in zip(_floats(surface_r), _floats(s_star), _floats(r_min),
                             _floats(r_max), strict=True):
        if abs(si) < 1e-12:
            continue
        a = (lo - r) / (si * dt)
        b = (hi - r) / (si * dt)
        rho_min = max(rho_min, min(a, b))
        rho_max = min(rho_max, max(a, b))
    return rho_min, rho_max


def _floats(v: Sequence[float] | FloatArray) -> list[float]:
    """Return the three components of ``v`` as Python floats."""
    out = v.tolist() if isinstance(v, np.ndarray) else [float(x) for x in v]
    if len(out) != 3:
        raise ValueError(f"a 3-vector was expected, got {len(out)} components")
    return out


__all__ = ["grasp_rate_range"]
