"""Exact solver of the step QP by parametrising the null space of ``A``.

Every solution of ``A x = b`` is ``x = x0 + N t`` (:func:`~._affine.affine_solutions`:
one SVD, the null-space dimension ``d`` decided with :data:`~._affine.RANK_RTOL`). Every
limit of the step, box or general row, is a row ``C_i x <= e_i`` of
:meth:`~dualarm_qp.step.StepProblem.inequalities` (unit norm), hence a row
``(C_i N) t <= e_i - C_i x0`` on ``t``:

* ``d = 0`` (a square nonsingular step such as the leader's 6 x 6): ``x = x0``,
  OPTIMAL if it meets every row, INFEASIBLE naming the rows it breaks otherwise.
* ``d = 1`` (the paper's step: a rigid six-joint leader and one sliding grasp): every
  row is an interval on the scalar ``t``; their intersection is exact and the
  minimiser ``t* = -z^T W (x0 - c) / z^T W z`` is clamped to it.
* ``d >= 2`` (a 6 x 8 step, both grasps sliding, a rank-deficient step at a singular
  pose): the dual active-set method of Goldfarb and Idnani (:mod:`._dense_qp`) on the
  ``d`` null-space coordinates. It needs no feasible start, cannot cycle on degenerate
  vertices (stated tie rules) and proves infeasibility by a row it cannot add.

A row whose normal does not move along the null space (``|C_i N| <= RANK_RTOL``) is a
condition on ``x0`` alone: met within ``feasibility_tol`` or the step is infeasible.

The answer is a claim (OPTIMAL or INFEASIBLE); :func:`~.certify.certify` checks it.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..step.problem import StepProblem
from ._affine import RANK_RTOL, affine_solutions, cost_root, problem_factor
from ._dense_qp import solve_dense_qp
from ._util import empty_box_failure
from .base import DEFAULT_TOLERANCE, Status, StepSolution, Tolerance, failed
from .registry import check_number, check_tolerance, register

FloatArray = NDArray[np.float64]


class NullspaceSolver:
    """Exact minimiser of Eq. 37 subject to ``A x = b``, the boxes and the rows.

    Parameters
    ----------
    feasibility_tol : float
        Violation [rad/s or m/s] below which a row counts as met (a barely empty
        interval is still accepted: its midpoint is returned).
    max_iter : int, optional
        Limit on the active-set additions and drops (``d >= 2``; default ``10 (k + d) +
        10`` for ``k`` rows).
    tol : Tolerance
        Tolerances of the certificate.
    """

    name = "nullspace"

    def __init__(self, *, feasibility_tol: float = 1e-10, max_iter: int | None = None,
                 tol: Tolerance = DEFAULT_TOLERANCE) -> None:
        check_number(self.name, "feasibility_tol", feasibility_tol, minimum=0.0, strict=True)
        if max_iter is not None:
            check_number(self.name, "max_iter", max_iter, integer=True, minimum=1)
        check_tolerance(self.name, tol)
        self.feasibility_tol = float(feasibility_tol)
        self.max_iter = max_iter
        self.tol = tol

    def solve(self, problem: StepProblem) -> StepSolution:
        """Solve one step exactly; see the module docstring."""
        start = time.perf_counter()
        empty = empty_box_failure(problem, self.name)
        if empty is not None:
            return empty
        aff = affine_solutions(problem.A, problem.b, problem_factor(problem))
        if aff is None:
            return failed(problem, Status.INFEASIBLE, self.name,
                          "A x = b has no solution (A is rank-deficient)",
                          time.perf_counter() - start, conflicts=())
        ineq = problem.inequalities()
        x0, N = aff.x0, aff.N
        M = ineq.C @ N
        f = ineq.e - ineq.C @ x0
        tol = self.feasibility_tol
        moving = np.abs(M).max(axis=1, initial=0.0) > RANK_RTOL
        fixed_broken = np.flatnonzero(~moving & (f < -tol))
        extras: dict[str, Any] = {"nullity": aff.nullity}
        if fixed_broken.size:
            return self._infeasible(problem, [int(i) for i in fixed_broken], start, extras)
        d = aff.nullity
        if d == 0:
            return StepSolution(x=x0, status=Status.OPTIMAL, solver=self.name,
                                solve_time=time.perf_counter() - start, extras=extras)
        R = cost_root(problem)
        RN = R[:, None] * N if R.ndim == 1 else R @ N
        r = R * (problem.center - x0) if R.ndim == 1 else R @ (problem.center - x0)
        Q, Rt = np.linalg.qr(RN)
        t_free = np.linalg.solve(Rt, Q.T @ r)
        rows = np.flatnonzero(moving)
        if d == 1:
            t, conflict = _interval(M[rows, 0], f[rows], float(t_free[0]), tol)
            if conflict is not None:
                return self._infeasible(problem, [int(rows[i]) for i in conflict],
                                        start, extras)
            x = x0 + N[:, 0] * t
        else:
            out = solve_dense_qp(Rt, t_free, M[rows], f[rows], feas_tol=tol,
                                 max_iter=self.max_iter)
            extras["iterations"] = out.iterations
            if out.status == "max_iter":
                return failed(problem, Status.ERROR, self.name,
                              f"active set did not converge in {out.iterations - 1} "
                              "additions and drops", time.perf_counter() - start, **extras)
            if out.status == "infeasible":
                involved = [int(rows[i]) for i in (*out.active.tolist(), out.blocking)]
                return self._infeasible(problem, involved, start, extras)
            x = x0 + N @ out.t
        return StepSolution(x=x, status=Status.OPTIMAL, solver=self.name,
                            solve_time=time.perf_counter() - start, extras=extras)

    def _infeasible(self, problem: StepProblem, rows: list[int], start: float,
                    extras: dict[str, Any]) -> StepSolution:
        conflicts = problem.inequalities().labels(rows)
        return failed(problem, Status.INFEASIBLE, self.name,
                      "no x meets A x = b within the limits; conflicting: "
                      + ", ".join(conflicts), time.perf_counter() - start,
                      conflicts=conflicts, **extras)


def _interval(c: FloatArray, f: FloatArray, t_free: float, tol: float
              ) -> tuple[float, tuple[int, int] | None]:
    """Clamp ``t_free`` to ``{t : c_i t <= f_i}``; ``(t, None)`` or ``(0, conflicting rows)``.

    Every ``c_i`` is nonzero (rows that do not move were checked before). An interval
    empty by at most ``tol`` (in units of ``x``: the rows are unit norm and the null
    direction has unit length) is rounding: its midpoint is returned.
    """
    ratio = f / c
    up = c > 0.0
    hi_rows = np.flatnonzero(up)
    lo_rows = np.flatnonzero(~up)
    t_hi, t_lo = np.inf, -np.inf
    i_hi = i_lo = -1
    if hi_rows.size:
        j = int(np.argmin(ratio[hi_rows]))
        i_hi, t_hi = int(hi_rows[j]), float(ratio[hi_rows[j]])
    if lo_rows.size:
        j = int(np.argmax(ratio[lo_rows]))
        i_lo, t_lo = int(lo_rows[j]), float(ratio[lo_rows[j]])
    if t_lo > t_hi:
        if t_lo - t_hi > 2.0 * tol:
            return 0.0, (i_lo, i_hi)
        return 0.5 * (t_lo + t_hi), None
    return min(max(t_free, t_lo), t_hi), None


register("nullspace", NullspaceSolver,
         description="exact: null-space parametrisation, interval (d=1) or dual active set",
         hard_bounds=True, takes_rows=True, dense_cost=True)
