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
When the null space of ``A`` is one-dimensional (every regular 6 x 7 step), a guess with
at most one active bound is decided in closed form on the line ``x0 + t z`` of
:mod:`._affine`: one SVD per call and scalar arithmetic per guess; on that line the
one stationarity condition is the projection on ``z``. With a larger null space (a
6 x 8 step, or a 6 x 7 step at a singular pose whose numerical rank is 5) every guess
goes through :func:`_solve_active`, which solves on the null space of the free columns
and checks that the gradient ``W (x - c) + A^T lam`` vanishes on every free variable.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..step.problem import StepProblem
from ._affine import AffineSet, affine_solutions, factor, least_distance

FloatArray = NDArray[np.float64]

#: Relative distances to a bound under which a bound is guessed active, tried in order.
ACTIVE_GUESSES = (1e-9, 1e-6, 1e-4)

#: Largest bound violation or wrong-signed multiplier (relative) accepted by the certificate.
PRIMAL_TOL = 1e-10
DUAL_TOL = 1e-9

#: A fixed bound whose variable moves by at most this (relative to ``max |z|``) along the
#: null direction is left to the general solve (the closed form would divide by it).
#: A routing threshold, not a rank decision: both paths are exact.
ZERO_STEP = 1e-8


def refine(problem: StepProblem, x: FloatArray) -> FloatArray | None:
    """Return the KKT-certified optimum near ``x``, or None if no nearby guess certifies.

    ``x`` is any approximate answer (the backend's last iterate). For each distance in
    :data:`ACTIVE_GUESSES`, the bounds that ``x`` meets or breaks within that distance
    are fixed at their value and the rest solved exactly; the first candidate whose free
    variables lie in their box and whose bound multipliers have the right sign is the
    optimum of the step QP (the QP is strictly convex, so the KKT point is unique).

    When the numerical null space of ``A`` (:data:`~._affine.RANK_RTOL`) is
    one-dimensional (every regular 6 x 7 step) each candidate is written in closed form
    on the line ``x0 + t z`` (:func:`_refine_1d`); the guesses it cannot decide that way,
    and every guess when the null space has another dimension, go through the general
    solve, which is the same certificate for any shape and checks stationarity on the
    whole null space.

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
    m, n = problem.A.shape
    if m and n <= m + 1:  # otherwise the null space has at least two dimensions
        aff = affine_solutions(problem.A, problem.b)
        if aff is not None and aff.nullity == 1:
            return _refine_1d(problem, x, aff)
    return _refine_general(problem, x)


def _refine_general(problem: StepProblem, x: FloatArray) -> FloatArray | None:
    """:func:`refine` for any shape: one equality-constrained solve per guess."""
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


def _refine_1d(problem: StepProblem, x: FloatArray, aff: AffineSet) -> FloatArray | None:
    """:func:`refine` on the line ``x0 + t z`` of a one-dimensional null space.

    The same guesses, in the same order, as :func:`_refine_general`, each decided by the
    same checks written in scalars. With no bound fixed, ``t`` is the unconstrained
    minimiser ``z^T W (c - x0) / z^T W z``; with one bound ``k`` fixed, ``t`` puts
    ``x_k`` on it, and stationarity ``W (x - c) + A^T lam = mu e_k`` projected on ``z``
    (``A z = 0``) gives the one multiplier ``mu = z^T W (x - c) / z_k``, whose sign is
    checked. ``x0`` is the minimum-norm solution, orthogonal to ``z``, so ``x0 + t z``
    does not cancel. Two or more fixed bounds (a degenerate vertex, or a zero-width
    box) or a fixed bound that hardly moves along ``z`` are left to
    :func:`_solve_active`.
    """
    lo, up = problem.lower.tolist(), problem.upper.tolist()
    lo_s = [max(1.0, abs(v)) for v in lo]  # scales of the bounds, as in _refine_general
    up_s = [max(1.0, abs(v)) for v in up]
    # A zero-width box fixes its variable whatever its multiplier: left to the general path.
    if any(u - v <= 1e-12 * s for v, u, s in zip(lo, up, lo_s, strict=True)):
        return _refine_general(problem, x)
    x0, z = aff.x0.tolist(), aff.N[:, 0].tolist()
    xs = x.tolist()
    n = len(xs)
    idx = range(n)
    zmax = max(map(abs, z))
    tried: set[tuple[int, ...]] = set()
    for rel in ACTIVE_GUESSES:
        # Side of each bound guessed active: -1 lower, +1 upper, 0 free.
        side = [0] * n
        for i in idx:
            xi = xs[i]
            a_lo = xi <= lo[i] + rel * lo_s[i]
            a_up = xi >= up[i] - rel * up_s[i]
            if a_lo and a_up:  # a tiny box: take the nearer side
                side[i] = -1 if abs(xi - lo[i]) <= abs(xi - up[i]) else 1
            elif a_lo:
                side[i] = -1
            elif a_up:
                side[i] = 1
        key = tuple(side)
        if key in tried:
            continue
        tried.add(key)
        fixed = [i for i in idx if side[i]]
        if len(fixed) > 1 or (fixed and abs(z[fixed[0]]) <= ZERO_STEP * zmax):
            cand = _solve_side(problem, side)
            if cand is not None:
                return cand
            continue
        cand = _candidate_1d(problem, side, fixed, (x0, z, lo, up))
        if cand is not None:
            return cand
    return None


def _candidate_1d(problem: StepProblem, side: list[int], fixed: list[int],
                  line: tuple[list[float], list[float], list[float], list[float]]
                  ) -> FloatArray | None:
    """Closed-form candidate of one guess (at most one fixed bound), if it certifies.

    ``line`` holds ``x0``, ``z``, ``lower`` and ``upper`` as lists.
    """
    x0, z, lo, up = line
    w, c = problem.weights.tolist(), problem.center.tolist()
    idx = range(len(x0))
    if fixed:
        k = fixed[0]
        bound = lo[k] if side[k] < 0 else up[k]
        t = (bound - x0[k]) / z[k]
    else:
        num = den = 0.0
        for i in idx:
            wz = w[i] * z[i]
            num += wz * (c[i] - x0[i])
            den += wz * z[i]
        t = num / den
    xc = [x0[i] + t * z[i] for i in idx]
    if fixed:
        xc[k] = bound
    cand = np.array(xc)
    b = problem.b
    scale_b = max(1.0, *map(abs, b.tolist()))
    if max(map(abs, (problem.A @ cand - b).tolist())) > 1e-9 * scale_b:
        return None
    for i in idx:
        if not side[i]:
            tol = PRIMAL_TOL * max(1.0, abs(lo[i]), abs(up[i]))
            if xc[i] < lo[i] - tol or xc[i] > up[i] + tol:
                return None
    if fixed:
        # Stationarity on the line: z^T (W (x - c) + A^T lam) = z_k mu, with A z = 0.
        gx = [w[i] * (xc[i] - c[i]) for i in idx]
        mu = sum([z[i] * gx[i] for i in idx]) / z[k]
        # The scale of _solve_active: max |W (x - c)| and max |A^T lam|, where
        # A^T lam = mu e_k - W (x - c).
        dtol = DUAL_TOL * max(1.0, max(map(abs, gx)), abs(mu - gx[k]))
        if (side[k] < 0 and mu < -dtol) or (side[k] > 0 and mu > dtol):
            return None
    return np.minimum(np.maximum(cand, problem.lower), problem.upper)


def _solve_side(problem: StepProblem, side: list[int]) -> FloatArray | None:
    """:func:`_solve_active` for a guess given as sides (-1 lower, +1 upper, 0 free)."""
    sides = np.array(side)
    return _solve_active(problem, sides < 0, sides > 0, np.zeros(sides.size, dtype=bool))


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
    dtol = DUAL_TOL * max(1.0, float(np.abs(grad).max()), float(np.abs(a_lam).max(
        initial=0.0)))
    if float(np.abs(g[free]).max(initial=0.0)) > dtol:
        return None
    if (g[at_lo & ~pinned] < -dtol).any() or (g[at_up & ~pinned] > dtol).any():
        return None
    return np.clip(x, lo, up)
