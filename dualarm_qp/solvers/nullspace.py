"""Exact solver of the step QP by parametrising the null space of ``A``.

Every solution of ``A x = b`` is ``x = x0 + N t`` (:func:`~._affine.null_basis`: the
null-space dimension ``d`` decided with :data:`~._affine.RANK_RTOL`, from a QR
factorisation where it proves full row rank, from one SVD otherwise). Every
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

The whole method is one call into the compiled kernel (``src/kernel/nullspace.cpp``);
:meth:`NullspaceSolver.solve` gathers the arrays and names the conflicting rows. In a
controller the solve and its certificate are one call
(:meth:`NullspaceSolver.solve_certified`, ``src/kernel/certified_step.cpp``).
"""

from __future__ import annotations

import time
from typing import Any

from .._compiled import kernel
from ..step.problem import StepProblem
from ._affine import cost_arrays, problem_basis
from ._util import empty_box_answer, empty_box_failure
from .base import DEFAULT_TOLERANCE, Status, StepSolution, Tolerance, failed
from .certify import certify, named_rows, verdict, verdict_fields
from .registry import check_number, check_tolerance, register


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
        rows = kernel.inequalities(problem.lower, problem.upper, problem.G, problem.h)
        w_diag, w_full, root_full = cost_arrays(problem)
        answer = kernel.solve_nullspace(
            problem.A, problem.b, problem_basis(problem), rows.C, rows.e, w_diag,
            w_full, root_full, problem.center, self.feasibility_tol, self._max_iter())
        return self._claim(problem, answer, start, rows)

    def solve_certified(self, problem: StepProblem, tol: Tolerance,
                        claims_bounds: bool = True) -> StepSolution:
        """Solve one step and certify the answer, in one kernel call.

        What :class:`~.registry.CertifiedSolver` calls for this solver: the same
        solve as :meth:`solve` and, for an optimum, the kernel's certificate of its
        ``x`` (the function :func:`~.certify.certify` calls) on the same basis of ``A``
        and the same rows, computed once; :func:`~.certify.verdict_fields` decides, as
        for every solver. An empty box is found by the same call, which then does not
        solve.
        """
        start = time.perf_counter()
        w_diag, w_full, root_full = cost_arrays(problem)
        step = kernel.solve_certified(
            problem.A, problem.b, problem.lower, problem.upper, problem.G, problem.h,
            w_diag, w_full, root_full, problem.center, self.feasibility_tol,
            self._max_iter(), claims_bounds, tol.equality, tol.bounds)
        code = step.code
        if code == _EMPTY_BOX:  # not solved: the one answer to an empty box
            return certify(problem, empty_box_answer(problem, self.name,
                                                     time.perf_counter() - start),
                           tol, claims_bounds=claims_bounds)
        reading = step.certificate
        if code == _OPTIMAL:  # an optimum: certified in one piece, without a claim first
            fields = verdict_fields(problem, Status.OPTIMAL, "", step.x, reading, tol,
                                    claims_bounds)
            if fields is not None:
                return StepSolution(**fields, scale=1.0,
                                    solve_time=time.perf_counter() - start,
                                    solver=self.name, extras=_extras(step))
        claim = self._claim(problem, step, start, step.rows)  # the rows named only if read
        if reading is None:  # not an optimum: the claim is certified as it is
            return certify(problem, claim, tol, claims_bounds=claims_bounds)
        return verdict(problem, claim, claim.x, reading, tol, claims_bounds,
                       time.perf_counter())

    def _max_iter(self) -> int:
        return -1 if self.max_iter is None else self.max_iter

    def _claim(self, problem: StepProblem, answer: kernel.StepAnswer | kernel.CertifiedStep,
               start: float, rows: kernel.Rows | None = None) -> StepSolution:
        """Return the solver's claim from the kernel's answer (OPTIMAL, or a failure)."""
        code = answer.code
        if code == _INCONSISTENT:
            return failed(problem, Status.INFEASIBLE, self.name,
                          "A x = b has no solution (A is rank-deficient)",
                          time.perf_counter() - start, conflicts=())
        extras = _extras(answer)
        if code == _INFEASIBLE:
            return self._infeasible(problem, answer.conflicts, start, extras, rows)
        if code == _MAX_ITER:
            return failed(problem, Status.ERROR, self.name,
                          f"active set did not converge in {answer.iterations - 1} "
                          "additions and drops", time.perf_counter() - start, **extras)
        return StepSolution(x=answer.x, status=Status.OPTIMAL, solver=self.name,
                            solve_time=time.perf_counter() - start, extras=extras)

    def _infeasible(self, problem: StepProblem, conflicting: list[int], start: float,
                    extras: dict[str, Any], rows: kernel.Rows | None = None
                    ) -> StepSolution:
        conflicts = named_rows(problem, rows).labels(conflicting)
        return failed(problem, Status.INFEASIBLE, self.name,
                      "no x meets A x = b within the limits; conflicting: "
                      + ", ".join(conflicts), time.perf_counter() - start,
                      conflicts=conflicts, **extras)


def _extras(answer: kernel.StepAnswer | kernel.CertifiedStep) -> dict[str, Any]:
    """Return the answer's null-space dimension, and its active-set iterations if counted."""
    extras: dict[str, Any] = {"nullity": answer.nullity}
    if answer.iterations >= 0:
        extras["iterations"] = answer.iterations
    return extras


#: The kernel's answer codes (src/kernel/nullspace.hpp); 0 is OPTIMAL. An empty box is
#: ``kernel.EMPTY_BOX_CODE`` (``kernel.solve_certified`` does not solve it).
_OPTIMAL, _INFEASIBLE, _INCONSISTENT, _MAX_ITER = 0, 1, 2, 3
_EMPTY_BOX: int = kernel.EMPTY_BOX_CODE


register("nullspace", NullspaceSolver,
         description="exact: null-space parametrisation, interval (d=1) or dual active set",
         hard_bounds=True, takes_rows=True, dense_cost=True, certifies_in_kernel=True)
