"""Active-set refinement of an approximate step QP answer (private).

First-order and interior-point backends stop at a tolerance; on the recorded steps the
sliding weight ``s7`` reaches 1e9, the multipliers reach 1e5 and more, and their
absolute dual tolerances cannot be met (see ``docs/benchmarks.md``). The backend's point
still tells which bounds are active. Given that guess, the step QP reduces to an
equality-constrained least-distance problem solved exactly, and the KKT conditions
(primal feasibility, stationarity on the whole null space of the free columns,
multiplier signs) either certify the result as the optimum or reject the guess. This is
what OSQP's own "polish" does, done here once for every backend, in the original
variables.

Every rank decision is an SVD at :data:`~._affine.RANK_RTOL` (:func:`~._affine.factor`).
Every guess, for any shape of the step, goes through one path (:func:`_solve_active`),
which solves on the null space of the free columns and checks that the gradient
``W (x - c) + A^T lam`` vanishes on every free variable. (A closed form on the line of
a one-dimensional null space used to decide the common guesses; it was a second
implementation of the same certificate, and is gone.)
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..step.problem import StepProblem
from ._affine import factor, least_distance

FloatArray = NDArray[np.float64]

#: Relative distances to a bound under which a bound is guessed active, tried in order.
ACTIVE_GUESSES = (1e-9, 1e-6, 1e-4)

#: Largest bound violation or wrong-signed multiplier (relative) accepted by the certificate.
PRIMAL_TOL = 1e-10
DUAL_TOL = 1e-9
#: Rounding allowance of the stationarity check: a thousand ulps of the gradient's largest
#: term.
ROUNDING = 1e3 * float(np.finfo(np.float64).eps)

def refine(problem: StepProblem, x: FloatArray) -> FloatArray | None:
    """Return the KKT-certified optimum near ``x``, or None if no nearby guess certifies.

    ``x`` is any approximate answer (the backend's last iterate). For each distance in
    :data:`ACTIVE_GUESSES`, the bounds that ``x`` meets or breaks within that distance
    are fixed at their value and the rest solved exactly; the first candidate whose free
    variables lie in their box and whose bound multipliers have the right sign is the
    optimum of the step QP (the QP is strictly convex, so the KKT point is unique).

    Parameters
    ----------
    problem : StepProblem
        The step (``x`` in [rad/s, m/s]).
    x : ndarray, shape (n,)
        Approximate answer.

    Returns
    -------
    ndarray or None
        The certified optimum, clipped into the box (it lies in it to 1e-10 relative).
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
    """Exact minimiser with the given bounds fixed, if it passes the KKT checks.

    The free variables are ``x_F = x0 + N t`` on the numerical null space of the free
    columns ``A_F`` (:func:`~._affine.factor`, rank at :data:`~._affine.RANK_RTOL`), with
    ``t`` minimising ``|W_F^1/2 (x0 + N t - c_F)|`` (:func:`~._affine.least_distance`).
    The multipliers are the minimum-norm ``lam`` of ``A_F^T lam = -W_F (x_F - c_F)``.
    The candidate is certified when ``A x = b`` holds, the free variables lie in their
    box, the gradient ``W (x - c) + A^T lam`` vanishes on every free variable
    (stationarity on the whole null space, not only its sign on the fixed ones) and has
    the sign of an active bound on every fixed variable.
    """
    A, b, w, c = problem.A, problem.b, problem.weights, problem.center
    at_lo = at_lo | pinned
    at_up = at_up & ~pinned
    fixed = at_lo | at_up
    free = ~fixed
    x = c.copy()
    x[at_lo] = problem.lower[at_lo]
    x[at_up] = problem.upper[at_up]
    f = factor(A[:, free])
    x_free = least_distance(f.N, f.solve(b - A[:, fixed] @ x[fixed]), w[free], c[free])
    x[free] = x_free
    if not np.isfinite(x).all():
        return None
    lam = f.solve_transposed(-w[free] * (x_free - c[free]))
    scale_b = max(1.0, float(np.abs(b).max(initial=0.0)))
    if problem.m and float(np.abs(A @ x - b).max()) > 1e-9 * scale_b:
        return None  # too few free variables for the task: the guess is wrong
    lo, up = problem.lower, problem.upper
    tol = PRIMAL_TOL * np.maximum(1.0, np.maximum(np.abs(lo), np.abs(up)))
    if (x[free] < lo[free] - tol[free]).any() or (x[free] > up[free] + tol[free]).any():
        return None
    # Stationarity: W (x - c) + A^T lam = mu_lo - mu_up, mu >= 0, mu = 0 when free.
    grad = w * (x - c)
    a_lam = A.T @ lam
    g = grad + a_lam
    # Relative to the size of the gradient's terms, plus the rounding of its largest term
    # w_i (x_i - c_i), which the multipliers carry to every variable: with a sliding
    # weight of 1e9 one ulp of the sliding speed is already 1e-7 of gradient.
    dtol = DUAL_TOL * max(1.0, float(np.abs(grad).max()), float(np.abs(a_lam).max(
        initial=0.0))) + ROUNDING * float((w * (np.abs(x) + np.abs(c))).max())
    if float(np.abs(g[free]).max(initial=0.0)) > dtol:
        return None
    if (g[at_lo & ~pinned] < -dtol).any() or (g[at_up & ~pinned] > dtol).any():
        return None
    return np.clip(x, lo, up)
