"""The fixed-grasp step of Zheng and Luh: the grasp does not slide.

The last ``n_grasp`` variables (sliding speeds) are held at zero and the joint rates
solve ``A[:, :n-k] xq = b``. For a square, nonsingular block this is the unique
solution; otherwise it is the solution nearest the centre in the ``S`` norm among the
exact solutions (the least-squares one if there is none, which verification then
reports as VIOLATION). The bounds are not enforced, only reported.
"""

from __future__ import annotations

import time

import numpy as np

from ..step.problem import StepProblem
from ._affine import factor
from .base import DEFAULT_TOLERANCE, Status, StepSolution, Tolerance
from .registry import check_tolerance, register


class FixedGraspSolver:
    """Zheng-Luh step with the grasp fixed (sliding speeds zero).

    Parameters
    ----------
    tol : Tolerance
        Tolerances of the certificate (:func:`~.certify.certify`).
    """

    name = "fixed_grasp"

    def __init__(self, *, tol: Tolerance = DEFAULT_TOLERANCE) -> None:
        check_tolerance(self.name, tol)
        self.tol = tol

    def solve(self, problem: StepProblem) -> StepSolution:
        """Solve for the joint rates with the grasp held still."""
        start = time.perf_counter()
        q = problem.n - problem.n_grasp
        A = problem.A[:, :q]
        c = problem.center[:q]
        inv_sqrt = 1.0 / np.sqrt(np.diag(problem.weight_matrix())[:q])
        # x = c + S^-1/2 y with y the least-norm solution of (A S^-1/2) y = b - A c.
        y = factor(A * inv_sqrt).solve(problem.b - A @ c)  # rank decided at RANK_RTOL
        x = np.zeros(problem.n)
        x[:q] = c + inv_sqrt * y
        elapsed = time.perf_counter() - start
        return StepSolution(x=x, status=Status.FEASIBLE, solver=self.name,
                            solve_time=elapsed, extras={"grasp_fixed": True})


register("fixed_grasp", FixedGraspSolver,
         description="Zheng-Luh: grasp fixed (sliding speeds 0), joint rates from A x = b",
         hard_bounds=False, takes_rows=False, dense_cost=False)
