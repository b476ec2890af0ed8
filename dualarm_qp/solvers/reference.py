"""The paper's reference step (Eq. 29 with the z-hat formula after Eq. 40).

    x    = A^+ b + (I - A^+ A) zhat,            A^+ = A^T (A A^T)^-1
    zhat = [P S P]^+ P S (c - A^+ b),           P = I - A^+ A

This is the exact minimiser of Eq. 37 on the affine set ``A x = b`` and it ignores the
bounds (Eqs. 33-34 only enter through the centre ``c``). It is implemented as the paper
writes it, pseudoinverses included, to serve as the reference; see ``nullspace`` for
an exact solver that also meets the bounds.
"""

from __future__ import annotations

import time

import numpy as np

from ..step.problem import StepProblem
from ._affine import problem_factor
from .base import DEFAULT_TOLERANCE, Status, StepSolution, Tolerance, failed
from .registry import check_tolerance, register


class ReferenceSolver:
    """Suh and Shin's pseudoinverse step; bound violations are reported as VIOLATION.

    Parameters
    ----------
    tol : Tolerance
        Tolerances of the certificate (:func:`~.certify.certify`).
    """

    name = "reference"

    def __init__(self, *, tol: Tolerance = DEFAULT_TOLERANCE) -> None:
        check_tolerance(self.name, tol)
        self.tol = tol

    def solve(self, problem: StepProblem) -> StepSolution:
        """Evaluate Eq. 29 with the optimal ``zhat``; never enforces the bounds."""
        start = time.perf_counter()
        A, b = problem.A, problem.b
        S = problem.weight_matrix()
        rank = problem_factor(problem).rank
        if rank < problem.m:  # decided at RANK_RTOL, not by an LU pivot
            return failed(problem, Status.ERROR, self.name,
                          f"J_f has rank {rank} < {problem.m} (RANK_RTOL): J_f^+ = "
                          "J_f^T (J_f J_f^T)^-1 is undefined",
                          time.perf_counter() - start)
        try:
            A_pinv = A.T @ np.linalg.inv(A @ A.T)  # J_f^+ = J_f^T (J_f J_f^T)^-1
        except np.linalg.LinAlgError as err:
            return failed(problem, Status.ERROR, self.name,
                          f"A A^T is singular, J_f^+ undefined: {err}",
                          time.perf_counter() - start)
        P = np.eye(problem.n) - A_pinv @ A  # projector onto the null space of A
        x_min_norm = A_pinv @ b
        zhat = _psd_pinv(P @ S @ P, problem.n - problem.m) @ P @ S @ (
            problem.center - x_min_norm)
        x = x_min_norm + P @ zhat
        elapsed = time.perf_counter() - start
        # The claim: the minimiser over A x = b. The certificate checks it (near a
        # singular pose the pseudoinverse's rounding can leave it off the minimiser).
        return StepSolution(x=x, status=Status.OPTIMAL, solver=self.name, solve_time=elapsed)


def _psd_pinv(M: np.ndarray, rank: int) -> np.ndarray:
    """Pseudoinverse of the symmetric PSD ``M`` whose exact rank is known.

    ``P S P`` has rank ``n - m`` (the null-space dimension of a full-rank ``A``); its
    other eigenvalues are rounding noise of order ``eps |S|``. A pseudoinverse with a
    relative cut-off (``np.linalg.pinv``'s default) inverts that noise when the null
    space is small or ``S`` is large, and returns an arbitrary, huge ``zhat``: keep
    exactly the ``rank`` largest eigenvalues instead.
    """
    if rank <= 0:
        return np.zeros_like(M)
    w, V = np.linalg.eigh(0.5 * (M + M.T))
    Vk = V[:, -rank:]
    return (Vk / w[-rank:]) @ Vk.T


register("reference", ReferenceSolver,
         description="Suh-Shin 1988 Eq. 29: pseudoinverse + optimal null-space term, no bounds",
         hard_bounds=False, takes_rows=False)
