"""Active-set refinement of an approximate step QP answer (private).

First-order and interior-point backends stop at a tolerance; on the recorded steps the
sliding weight ``s7`` reaches 1e9, the multipliers reach 1e5 and more, and their
absolute dual tolerances cannot be met (see ``docs/benchmarks.md``). The backend's point
still tells which bounds are active. Given that guess, the step QP reduces to an
equality-constrained least-distance problem solved exactly by one small factorisation,
and the KKT conditions (primal feasibility, multiplier signs) either certify the result
as the optimum or reject the guess. This is what OSQP's own "polish" does, done here
once for every backend, in the original variables.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..step.problem import StepProblem

FloatArray = NDArray[np.float64]

#: Relative distances to a bound under which a bound is guessed active, tried in order.
ACTIVE_GUESSES = (1e-9, 1e-6, 1e-4)

#: Largest bound violation or wrong-signed multiplier (relative) accepted by the certificate.
PRIMAL_TOL = 1e-10
DUAL_TOL = 1e-9


def refine(problem: StepProblem, x: FloatArray) -> FloatArray | None:
    """Return the KKT-certified optimum near ``x``, or None if no nearby guess certifies.

    ``x`` is any approximate answer (the backend's last iterate). For each distance in
    :data:`ACTIVE_GUESSES`, the bounds that ``x`` meets or breaks within that distance
    are fixed at their value and the rest solved exactly; the first candidate whose free
    variables lie in their box and whose bound multipliers have the right sign is the
    optimum of the step QP (the QP is strictly convex, so the KKT point is unique).
    """
    if not np.isfinite(x).all():
        return None
    lower, upper = problem.lower, problem.upper
    # A zero-width box fixes its variable whatever the sign of its multiplier.
    pinned = upper - lower <= 1e-12 * np.maximum(1.0, np.abs(lower))
    tried: set[bytes] = set()
    for rel in ACTIVE_GUESSES:
        at_lo = x <= lower + rel * np.maximum(1.0, np.abs(lower))
        at_up = x >= upper - rel * np.maximum(1.0, np.abs(upper))
        both = at_lo & at_up & ~pinned  # a tiny box: take the nearer side
        if both.any():
            nearer_lo = np.abs(x - lower) <= np.abs(x - upper)
            at_lo = at_lo & (~both | nearer_lo)
            at_up = at_up & (~both | ~nearer_lo)
        key = np.packbits(np.concatenate([at_lo, at_up])).tobytes()
        if key in tried:
            continue
        tried.add(key)
        cand = _solve_active(problem, at_lo, at_up, pinned)
        if cand is not None:
            return cand
    return None


def _solve_active(problem: StepProblem, at_lo: NDArray[np.bool_], at_up: NDArray[np.bool_],
                  pinned: NDArray[np.bool_]) -> FloatArray | None:
    """Exact minimiser with the given bounds fixed, if it passes the KKT checks."""
    A, b, w, c = problem.A, problem.b, problem.weights, problem.center
    at_lo = at_lo | pinned
    at_up = at_up & ~pinned
    fixed = at_lo | at_up
    free = ~fixed
    x = c.copy()
    x[at_lo] = problem.lower[at_lo]
    x[at_up] = problem.upper[at_up]
    Af = A[:, free]
    rhs = b - A[:, fixed] @ x[fixed]
    if problem.m:
        # Free part: x_f = c_f - W_f^-1 A_f^T lam with A_f x_f = rhs, i.e.
        # (A_f W_f^-1 A_f^T) lam = A_f c_f - rhs.
        winv = 1.0 / w[free]
        M = (Af * winv) @ Af.T
        r = Af @ c[free] - rhs
        try:
            lam = np.linalg.solve(M, r)
        except np.linalg.LinAlgError:
            return None
        if not np.isfinite(lam).all():
            return None
        x[free] = c[free] - winv * (Af.T @ lam)
    else:
        lam = np.zeros(0)
    scale_b = max(1.0, float(np.abs(b).max(initial=0.0)))
    if problem.m and float(np.abs(A @ x - b).max()) > 1e-9 * scale_b:
        return None  # too few free variables for the task: the guess is wrong
    lo, up = problem.lower, problem.upper
    tol = PRIMAL_TOL * np.maximum(1.0, np.maximum(np.abs(lo), np.abs(up)))
    if (x[free] < lo[free] - tol[free]).any() or (x[free] > up[free] + tol[free]).any():
        return None
    # Stationarity: W (x - c) + A^T lam = mu_lo - mu_up with mu >= 0.
    g = w * (x - c) + A.T @ lam
    dual_scale = max(1.0, float(np.abs(w * (x - c)).max()), float(np.abs(A.T @ lam).max(
        initial=0.0)))
    dtol = DUAL_TOL * dual_scale
    if (g[at_lo & ~pinned] < -dtol).any() or (g[at_up & ~pinned] > dtol).any():
        return None
    return np.clip(x, lo, up)
