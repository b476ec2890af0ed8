"""Active-set refinement of an approximate step QP answer (private).

First-order and interior-point backends stop at a tolerance; on the recorded steps the
sliding weight ``s7`` reaches 1e9, the multipliers reach 1e5 and more, and their
absolute dual tolerances cannot be met (see ``docs/benchmarks.md``). The backend's point
still tells which bounds are active. Given that guess, the step QP reduces to an
equality-constrained least-distance problem solved exactly by one small factorisation,
and the KKT conditions (primal feasibility, multiplier signs) either certify the result
as the optimum or reject the guess. This is what OSQP's own "polish" does, done here
once for every backend, in the original variables.

With a one-dimensional null space (every 6 x 7 step) a guess with at most one active
bound is decided in closed form on the line ``x0 + t z`` of :mod:`._affine`: one 6 x 6
LU solve per call and scalar arithmetic per guess. This is also the more accurate form:
the general path's normal equations ``A_f W_f^-1 A_f^T`` reach a condition number of
about 5e9 when ``s7`` is 1e9, and its answers are then off by up to about 1e-8 (enough
for its equality check to reject some optima that the closed form certifies).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..step.problem import StepProblem
from ._affine import AffineSet, affine_solutions

FloatArray = NDArray[np.float64]

#: Relative distances to a bound under which a bound is guessed active, tried in order.
ACTIVE_GUESSES = (1e-9, 1e-6, 1e-4)

#: Largest bound violation or wrong-signed multiplier (relative) accepted by the certificate.
PRIMAL_TOL = 1e-10
DUAL_TOL = 1e-9

#: A fixed bound whose variable moves by at most this (relative to ``max |z|``) along the
#: null direction is left to the general solve (the closed form would divide by it).
ZERO_STEP = 1e-8

#: ``max |x0| / max(1, max |x|)`` above which the closed form's ``x0 + t z`` could lose
#: more than about 4 digits to cancellation: the general solve is used instead.
GROWTH_LIMIT = 1e4


def refine(problem: StepProblem, x: FloatArray) -> FloatArray | None:
    """Return the KKT-certified optimum near ``x``, or None if no nearby guess certifies.

    ``x`` is any approximate answer (the backend's last iterate). For each distance in
    :data:`ACTIVE_GUESSES`, the bounds that ``x`` meets or breaks within that distance
    are fixed at their value and the rest solved exactly; the first candidate whose free
    variables lie in their box and whose bound multipliers have the right sign is the
    optimum of the step QP (the QP is strictly convex, so the KKT point is unique).

    With a one-dimensional null space (``n = m + 1``, every step of the paper) each
    candidate is written in closed form on the line ``x0 + t z`` (:func:`_refine_1d`);
    the guesses it cannot decide that way go through the general solve, which is the
    same certificate for any shape.
    """
    if not np.isfinite(x).all():
        return None
    m, n = problem.A.shape
    if m and n == m + 1:
        aff = affine_solutions(problem.A, problem.b)
        if aff is not None and aff.N.shape[1] == 1:
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
    checked. Two or more fixed bounds (a degenerate vertex, or a zero-width box), a
    fixed bound that hardly moves along ``z``, or a large pivoted ``x0`` (cancellation
    in ``x0 + t z``) are left to :func:`_solve_active`.
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
    x0max = max(map(abs, x0))
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
        cand = _candidate_1d(problem, side, fixed, (x0, z, lo, up), x0max)
        if cand is _UNDECIDED:
            cand = _solve_side(problem, side)
        if cand is not None:
            return cand
    return None


#: Returned by :func:`_candidate_1d` when the closed form is not accurate enough.
_UNDECIDED = np.zeros(0)


def _candidate_1d(problem: StepProblem, side: list[int], fixed: list[int],
                  line: tuple[list[float], list[float], list[float], list[float]],
                  x0max: float) -> FloatArray | None:
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
    if x0max > GROWTH_LIMIT * max(1.0, max(map(abs, xc))):
        return _UNDECIDED
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
