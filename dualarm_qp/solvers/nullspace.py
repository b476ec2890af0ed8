"""Exact solver of the step QP by parametrising the null space of ``A``.

Every solution of ``A x = b`` is ``x = x0 + N t`` (:func:`~._affine.affine_solutions`).

* One redundant variable (the paper's 6 x 7 step, d = 1): the cost Eq. 37 is a scalar
  quadratic in ``t``, the box gives an interval ``[t_lo, t_hi]``, and the minimiser is
  ``t* = -z^T S (x0 - c) / z^T S z`` clamped to it. One 6 x 6 LU solve, no SVD.
* Several redundant variables (d > 1, e.g. 6 x 8): an exact primal active-set method
  on the box, started from a feasible point of the LP in :mod:`._affine`.

Infeasible steps (empty box, empty interval, inconsistent equality) are reported as
INFEASIBLE with the conflicting bounds in ``message`` and ``extras["conflicts"]``.
"""

from __future__ import annotations

import operator
import time
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..step.problem import StepProblem
from ._affine import PIVOT_GROWTH_LIMIT, AffineSet, affine_solutions, max_task_scale
from ._util import bound_label, empty_box_failure
from .base import (
    DEFAULT_TOLERANCE,
    Status,
    StepSolution,
    Tolerance,
    failed,
    verified_solution,
)
from .registry import register

FloatArray = NDArray[np.float64]


class NullspaceSolver:
    """Exact minimiser of Eq. 37 subject to ``A x = b`` and the box.

    Parameters
    ----------
    feasibility_tol : float
        Bound violation [rad/s or m/s] below which a barely empty interval is still
        accepted (its midpoint is returned); beyond it the step is infeasible.
    max_iter : int
        Iteration limit of the active-set method (null space dimension > 1).
    tol : Tolerance
        Tolerances used by :func:`~.base.verify`.
    """

    name = "nullspace"

    def __init__(self, *, feasibility_tol: float = 1e-10, max_iter: int = 200,
                 tol: Tolerance = DEFAULT_TOLERANCE) -> None:
        self.feasibility_tol = float(feasibility_tol)
        self.max_iter = int(max_iter)
        self.tol = tol

    def solve(self, problem: StepProblem) -> StepSolution:
        """Solve one step exactly; see the module docstring."""
        start = time.perf_counter()
        lower, upper = problem.lower.tolist(), problem.upper.tolist()
        empty = (empty_box_failure(problem, self.name)
                 if any(map(operator.gt, lower, upper)) else None)
        if empty is not None:
            return empty
        extras: dict[str, Any] = {}
        x: FloatArray | None = None
        conflicts: tuple[str, ...] = ()
        robust = False
        while True:
            aff = affine_solutions(problem.A, problem.b, robust=robust)
            if aff is None:
                return failed(problem, Status.INFEASIBLE, self.name,
                              "A x = b has no solution (A is rank-deficient)",
                              time.perf_counter() - start, conflicts=())
            growth = 0.0
            if aff.N.shape[1] <= 1:
                x, conflicts, growth = self._interval(problem, aff, lower, upper)
            else:
                x, conflicts, extras["iterations"] = self._active_set(problem)
            # The pivoted x0 may be large and cancel in x0 + t z: redo with the SVD.
            if not aff.pivoted or (x is not None and growth <= PIVOT_GROWTH_LIMIT):
                break
            robust = True
        elapsed = time.perf_counter() - start
        extras["nullity"] = aff.N.shape[1]
        if x is None:
            if "iterations" in extras and extras["iterations"] > self.max_iter:
                return failed(problem, Status.ERROR, self.name,
                              f"active set did not converge in {self.max_iter} iterations",
                              elapsed, **extras)
            return failed(problem, Status.INFEASIBLE, self.name,
                          "no x meets A x = b within the bounds; conflicting bounds: "
                          + ", ".join(conflicts), elapsed, conflicts=conflicts, **extras)
        return verified_solution(problem, x, Status.OPTIMAL, solver=self.name, tol=self.tol,
                                 solve_time=elapsed, extras=extras)

    def _interval(self, problem: StepProblem, aff: AffineSet, los: list[float],
                  ups: list[float]) -> tuple[FloatArray | None, tuple[str, ...], float]:
        """Minimise over ``x = x0 + t z``: clamp the scalar minimiser to the bound interval.

        ``los`` and ``ups`` are the bounds as lists. Returns ``(x or None, conflicts,
        growth)`` with ``growth = max|x0| / max|x|``. Plain Python floats: at n = 7
        each numpy call costs more than the arithmetic.
        """
        xs = aff.x0.tolist()
        zs = aff.N[:, 0].tolist() if aff.N.shape[1] else [0.0] * len(xs)
        z_max = max(max(zs), -min(zs))
        z_tiny = 1e-13 * z_max
        tol = self.feasibility_tol
        curvature = slope = 0.0  # z^T S z and z^T S (x0 - c)
        t_lo, t_hi = -np.inf, np.inf
        why_lo = why_hi = (0, False)  # (variable, is its upper bound) that set t_lo / t_hi
        for i, (xi, zi, lo, up, wi, ci) in enumerate(zip(
                xs, zs, los, ups, problem.weights.tolist(), problem.center.tolist(),
                strict=True)):
            if zi > z_tiny:
                a, b = (lo - xi) / zi, (up - xi) / zi
            elif zi < -z_tiny:
                a, b = (up - xi) / zi, (lo - xi) / zi
            else:  # the null direction does not move x_i
                if xi < lo - tol or xi > up + tol:
                    return None, (bound_label(problem, i, xi > up),), 0.0
                continue
            curvature += wi * zi * zi
            slope += wi * zi * (xi - ci)
            if a > t_lo:
                t_lo, why_lo = a, (i, zi < 0.0)
            if b < t_hi:
                t_hi, why_hi = b, (i, zi > 0.0)
        t = -slope / curvature if curvature > 0.0 else 0.0
        if t_lo > t_hi:
            if (t_lo - t_hi) * z_max > 2.0 * tol:  # not just rounding: infeasible
                return None, (bound_label(problem, *why_lo), bound_label(problem, *why_hi)), 0.0
            t = 0.5 * (t_lo + t_hi)
        t = min(max(t, t_lo), t_hi)
        x = [xi + t * zi for xi, zi in zip(xs, zs, strict=True)]
        x_max, x0_max = max(max(x), -min(x)), max(max(xs), -min(xs))
        if x_max > 0.0:
            growth = x0_max / x_max
        else:  # x = 0, or NaN from an overflowing pivot (then growth = inf: retry)
            growth = 0.0 if x0_max == 0.0 else np.inf
        return np.array(x), (), growth

    def _active_set(self, problem: StepProblem
                    ) -> tuple[FloatArray | None, tuple[str, ...], int]:
        """Primal active-set method in ``x``; a working-set variable is held at its bound.

        Returns ``(x, conflicts, iterations)``; ``x`` is None when infeasible (conflicts
        set) or when the iteration limit was hit (``iterations > max_iter``).
        """
        start = max_task_scale(problem, cap=1.0)
        if start.scale is None or start.x is None or start.scale < 1.0 - 1e-9:
            return None, start.blocking or problem.names, 0
        lower, upper = problem.lower, problem.upper
        x = start.x
        side = np.zeros(problem.n, dtype=np.int8)  # -1: at lower, +1: at upper, 0: free
        for it in range(1, self.max_iter + 1):
            target, mu = _equality_qp(problem, side, x)
            step = target - x
            if float(np.abs(step).max()) <= 1e-12 * (1.0 + float(np.abs(x).max())):
                x = target
                # Lower bound needs mu >= 0, upper bound mu <= 0.
                wrong = -side * mu
                j = int(np.argmin(wrong))
                grad_scale = 1.0 + float(np.abs(problem.weights * (x - problem.center)).max())
                if side[j] == 0 or wrong[j] >= -1e-11 * grad_scale:
                    return x, (), it
                side[j] = 0
                continue
            alpha, block, block_side = 1.0, -1, 0
            for i in np.flatnonzero((side == 0) & (step != 0.0)):
                p = step[i]
                bound, s = (lower[i], -1) if p < 0 else (upper[i], 1)
                ratio = max((bound - x[i]) / p, 0.0)
                if ratio < alpha:
                    alpha, block, block_side = ratio, int(i), s
            x = x + alpha * step
            if block >= 0:
                side[block] = block_side
                x[block] = lower[block] if block_side < 0 else upper[block]
        return None, (), self.max_iter + 1


def _equality_qp(problem: StepProblem, side: NDArray[np.int8], x: FloatArray
                 ) -> tuple[FloatArray, FloatArray]:
    """Minimise Eq. 37 with ``A x = b`` and the working-set variables at their bounds.

    Returns the minimiser and the bound multipliers ``mu`` (zero off the working set),
    from ``S (x - c) = A^T lambda + mu``.
    """
    w, c, A = problem.weights, problem.center, problem.A
    free = side == 0
    target = np.where(side < 0, problem.lower, np.where(side > 0, problem.upper, x))
    rhs = problem.b - A[:, ~free] @ target[~free]
    inv_sqrt = 1.0 / np.sqrt(w[free])
    scaled = A[:, free] * inv_sqrt
    y = np.linalg.lstsq(scaled, rhs - A[:, free] @ c[free], rcond=None)[0]
    target[free] = c[free] + inv_sqrt * y
    grad = w * (target - c)
    lam = np.linalg.lstsq(A[:, free].T, grad[free], rcond=None)[0]
    mu = np.where(free, 0.0, grad - A.T @ lam)
    return target, mu


register("nullspace", NullspaceSolver,
         description="exact: null-space parametrisation, scalar clamp (d=1) or active set",
         hard_bounds=True)
