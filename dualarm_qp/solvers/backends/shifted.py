"""The step QP as every backend sees it: in ``y = x - c``, with the cost normalised.

    minimise    1/2 y^T W y
    subject to  A y = b - A c,   G y <= h - G c,   lower - c <= y <= upper - c.

The shift (Eq. 37 becomes ``y^T S y`` with no linear term) measurably helps the
interior-point backends (piqp, clarabel) and does not hurt the others. The cost is
divided by ``max(S)`` (:func:`cost_weights`; the minimiser is the same).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ...step.problem import StepProblem

FloatArray = NDArray[np.float64]


def cost_weights(weights: FloatArray) -> FloatArray:
    """Return the diagonal of the cost the backends see: ``S / max(S)`` (largest 1).

    Dividing the cost by a constant leaves the minimiser unchanged, and it keeps the
    first-order backends' penalties above the cost's curvature: with ``s7 = 1e9`` and
    the raw ``S``, proxqp's smallest penalty (``1 / mu_min_eq = 1e9``) no longer
    dominates the cost, and on 1,975 recorded feasible steps 349 stalled at their
    iteration limit with ``|A y - b| ~ 3``; normalised, they solve in under ten
    iterations.
    """
    top = float(weights.max())
    return weights / top if top > 0.0 else weights.copy()


def cost_matrix(weights: FloatArray) -> FloatArray:
    """Return the cost matrix the backends see: ``W / max |W|`` (diagonal or full, as given)."""
    if weights.ndim == 1:
        return np.diag(cost_weights(weights))
    top = float(np.abs(weights).max(initial=0.0))
    return weights / top if top > 0.0 else weights.copy()


def shifted_rows(problem: StepProblem) -> tuple[FloatArray, FloatArray]:
    """Return the general rows in ``y = x - c``: ``(G, h - G c)``, rows with a finite ``h`` only."""
    keep = np.isfinite(problem.h)
    G = problem.G[keep]
    return G, problem.h[keep] - G @ problem.center


def shifted_box(problem: StepProblem) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Return the shifted data ``(b - A c, lower - c, upper - c)``."""
    c = problem.center
    return problem.b - problem.A @ c, problem.lower - c, problem.upper - c


__all__ = ["cost_matrix", "cost_weights", "shifted_box", "shifted_rows"]
