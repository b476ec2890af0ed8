"""The call through qpsolvers: one ``qpsolvers.solve_problem`` on the shifted step QP.

Every backend without a native path goes this way (daqp, clarabel, piqp, highs,
quadprog, ...), and osqp and proxsuite do too when the cost is a full matrix.
qpsolvers imports every installed backend when it is imported (a tenth of a second or
more): it is imported at the first call, or when a backend's availability is first
asked, not with this module.
"""

from __future__ import annotations

import warnings
from typing import TYPE_CHECKING, Any

import numpy as np

from ...step.problem import StepProblem
from .answer import BackendAnswer
from .base import Backend
from .shifted import cost_matrix, shifted_rows

if TYPE_CHECKING:
    import scipy.sparse as sp


def solve_with_qpsolvers(backend: Backend, problem: StepProblem, options: dict[str, Any]
                         ) -> BackendAnswer:
    """Solve ``problem`` with ``backend`` through ``qpsolvers.solve_problem``.

    The backend's status text becomes the answer's; it says infeasible when the text
    says so (:meth:`Backend.says_infeasible`), or when a backend that finds no solution
    only for inconsistent constraints (quadprog) found none.
    """
    import qpsolvers
    c = problem.center
    P: np.ndarray | sp.csc_matrix = (cost_matrix(problem.weights)
                                     if backend.normalise_cost else problem.weight_matrix())
    A: np.ndarray | sp.csc_matrix = problem.A
    G: np.ndarray | sp.csc_matrix | None = None
    h = None
    if problem.p:
        G, h = shifted_rows(problem)
    if backend.sparse:
        import scipy.sparse as sp  # with a sparse backend only (0.2 s to import)

        P, A = sp.csc_matrix(P), sp.csc_matrix(A)
        G = None if G is None else sp.csc_matrix(G)
    qp = qpsolvers.Problem(P, np.zeros(problem.n), G=G, h=h, A=A,
                           b=problem.b - problem.A @ c,
                           lb=problem.lower - c, ub=problem.upper - c)
    initvals = None
    if backend.warm_start and problem.x_prev is not None:
        initvals = problem.x_prev - c
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            result = qpsolvers.solve_problem(qp, solver=backend.solver, initvals=initvals,
                                             **options)
        except ValueError as err:
            if backend.infeasible_when_not_found:  # quadprog: "inconsistent"
                return BackendAnswer(problem, None, False, True, str(err))
            raise
    text = status_text(result.extras)
    y = None if result.x is None else np.asarray(result.x, dtype=np.float64)
    infeasible = backend.says_infeasible(text) or (
        backend.infeasible_when_not_found and not result.found)
    return BackendAnswer(problem, y, bool(result.found), infeasible, text)


def status_text(extras: dict[str, Any]) -> str:
    """Return the backend status found in qpsolvers' ``Solution.extras``, as text ('' if none)."""
    if "status" in extras:
        return str(extras["status"])
    info = extras.get("info")
    for attr in ("status", "status_val"):
        if info is not None and hasattr(info, attr):
            return str(getattr(info, attr))
    return ""


def installed(solver: str) -> bool:
    """Whether qpsolvers can import the backend ``solver``."""
    import qpsolvers

    return solver in qpsolvers.available_solvers


__all__ = ["installed", "solve_with_qpsolvers", "status_text"]
