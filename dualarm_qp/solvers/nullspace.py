"""Exact solver of the step QP by parametrising the null space of ``A``.

Every solution of ``A x = b`` is ``x = x0 + N t`` (:func:`~._affine.affine_solutions`:
one SVD, the null-space dimension ``d`` decided with :data:`~._affine.RANK_RTOL`).

* No redundant variable (a square nonsingular step such as the leader's 6 x 6, d = 0):
  ``x = x0 = A^-1 b``, OPTIMAL if it lies in the box, INFEASIBLE naming the bound it
  breaks otherwise.
* One redundant variable (the paper's step: a rigid six-joint leader and one sliding
  grasp, d = 1): the cost Eq. 37 is a scalar
  quadratic in ``t``, the box gives an interval ``[t_lo, t_hi]``, and the minimiser is
  ``t* = -z^T S (x0 - c) / z^T S z`` clamped to it.
* Several redundant variables (d > 1: a 6 x 8 step, or a numerically rank-deficient
  6 x 7 step at a singular pose): an exact primal active-set method on the box,
  started from a feasible point of the LP in :mod:`._affine`; each iteration solves
  the equality-constrained subproblem on the null space of the free columns.

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
from ._affine import (
    RANK_RTOL,
    AffineSet,
    TaskScale,
    affine_solutions,
    factor,
    least_distance,
    max_task_scale,
)
from ._util import bound_label, empty_box_failure
from .base import (
    DEFAULT_TOLERANCE,
    Status,
    StepSolution,
    Tolerance,
    failed,
    verified_solution,
)
from .registry import check_number, check_tolerance, register

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
        check_number(self.name, "feasibility_tol", feasibility_tol, minimum=0.0, strict=True)
        check_number(self.name, "max_iter", max_iter, integer=True, minimum=1)
        check_tolerance(self.name, tol)
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
        aff = affine_solutions(problem.A, problem.b)
        if aff is None:
            return failed(problem, Status.INFEASIBLE, self.name,
                          "A x = b has no solution (A is rank-deficient)",
                          time.perf_counter() - start, conflicts=())
        x: FloatArray | None
        if aff.nullity <= 1:
            x, conflicts = self._interval(problem, aff, lower, upper)
        else:
            x, conflicts, extras["iterations"], reach = self._active_set(problem)
            if reach is not None:  # the task-scale LP ran: the policy may reuse it
                extras["task_scale"] = reach
        elapsed = time.perf_counter() - start
        extras["nullity"] = aff.nullity
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
                  ups: list[float]) -> tuple[FloatArray | None, tuple[str, ...]]:
        """Minimise over ``x = x0 + t z``: clamp the scalar minimiser to the bound interval.

        ``los`` and ``ups`` are the bounds as lists [rad/s, m/s]. With no null direction
        (square nonsingular ``A``) ``x = x0``, checked against the box. A component
        ``|z_i| <= RANK_RTOL * max |z|`` does not move ``x_i`` (see
        :func:`~._affine.moves`). Returns ``(x or None, conflicts)``. Plain Python
        floats: at n = 7 each numpy call costs more than the arithmetic.
        """
        xs = aff.x0.tolist()
        zs = aff.N[:, 0].tolist() if aff.nullity else [0.0] * len(xs)
        z_max = max(max(zs), -min(zs))
        z_tiny = RANK_RTOL * z_max
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
            else:  # the null direction does not move x_i (or there is none)
                if xi < lo - tol or xi > up + tol:
                    return None, (bound_label(problem, i, xi > up),)
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
                return None, (bound_label(problem, *why_lo), bound_label(problem, *why_hi))
            t = 0.5 * (t_lo + t_hi)
        t = min(max(t, t_lo), t_hi)
        return np.array([xi + t * zi for xi, zi in zip(xs, zs, strict=True)]), ()

    def _active_set(self, problem: StepProblem
                    ) -> tuple[FloatArray | None, tuple[str, ...], int, TaskScale | None]:
        """Primal active-set method in ``x``; a working-set variable is held at its bound.

        Returns ``(x, conflicts, iterations, task scale)``; ``x`` is None when infeasible
        (conflicts set) or when the iteration limit was hit (``iterations > max_iter``);
        the task scale is the LP's (:func:`~._affine.max_task_scale` at cap 1) when the
        start needed it, else None.
        """
        lower, upper = problem.lower, problem.upper
        side = np.zeros(problem.n, dtype=np.int8)  # -1: at lower, +1: at upper, 0: free
        found = self._start(problem, side)
        reach: TaskScale | None = None
        if found is None:  # a feasible start from the LP of the largest task scale
            reach = max_task_scale(problem, cap=1.0)
            if reach.scale is None or reach.x is None or reach.scale < 1.0 - 1e-9:
                return None, reach.blocking or problem.names, 0, reach
            x = reach.x
            side[:] = 0
        else:
            x = found
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
                    return x, (), it, reach
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
        return None, (), self.max_iter + 1, reach


    def _start(self, problem: StepProblem, side: NDArray[np.int8]) -> FloatArray | None:
        """Return a feasible start for the active set found without an LP, or None.

        First the minimiser on the whole affine set (no bound held): inside the box it
        is the answer itself. Then the warm start ``x_prev`` itself, when it meets the
        equality and the box (the policy hands the task-scale LP's point to the scaled
        problem this way), and last the minimiser with ``x_prev``'s working set held, if
        it lies in the box. ``side`` is set to the working set of the point returned.
        """
        lower, upper, n = problem.lower, problem.upper, problem.n
        scale = 1.0 + float(np.abs(problem.b).max(initial=0.0))

        def feasible(x: FloatArray) -> bool:
            return bool(np.all(x >= lower) and np.all(x <= upper) and float(
                np.abs(problem.A @ x - problem.b).max(initial=0.0)) <= 1e-10 * scale)

        x, _ = _equality_qp(problem, side, np.clip(np.zeros(n), lower, upper))
        if feasible(x):
            return x
        xp = problem.x_prev
        if xp is None:
            return None
        held = np.where(xp <= lower, -1, np.where(xp >= upper, 1, 0)).astype(np.int8)
        if feasible(xp):
            side[:] = held
            return np.where(held < 0, lower, np.where(held > 0, upper, xp))
        if held.any():
            x, _ = _equality_qp(problem, held, np.clip(np.zeros(n), lower, upper))
            if feasible(x):
                side[:] = held
                return x
        return None


def _equality_qp(problem: StepProblem, side: NDArray[np.int8], x: FloatArray
                 ) -> tuple[FloatArray, FloatArray]:
    """Minimise Eq. 37 with ``A x = b`` and the working-set variables at their bounds.

    The free part is written ``x_F = x0 + N t`` on the numerical null space of the free
    columns ``A_F`` (:func:`~._affine.factor`, rank at :data:`~._affine.RANK_RTOL`);
    ``t`` minimises ``|S_F^1/2 (x0 + N t - c_F)|`` (:func:`~._affine.least_distance`,
    no rank decision). ``x`` is the current iterate: it
    meets the equality, so the right-hand side lies in the range of ``A_F``.

    Returns the minimiser and the bound multipliers ``mu`` (zero off the working set),
    from ``S (x - c) = A^T lambda + mu`` with the minimum-norm ``lambda``.
    """
    w, c, A = problem.weights, problem.center, problem.A
    free = side == 0
    target = np.where(side < 0, problem.lower, np.where(side > 0, problem.upper, x))
    rhs = problem.b - A[:, ~free] @ target[~free]
    f = factor(A[:, free])
    target[free] = least_distance(f.N, f.solve(rhs), w[free], c[free])
    grad = w * (target - c)
    lam = f.solve_transposed(grad[free])
    mu = np.where(free, 0.0, grad - A.T @ lam)
    return target, mu


register("nullspace", NullspaceSolver,
         description="exact: null-space parametrisation, scalar clamp (d=1) or active set",
         hard_bounds=True)
