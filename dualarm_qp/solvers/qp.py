"""The step as a quadratic program, solved by any backend of qpsolvers (``qp:<backend>``).

The QP is written in the shifted variable ``y = x - c`` (Eq. 37 becomes ``y^T S y``
with no linear term), which measurably helps the interior-point backends (piqp,
clarabel) and does not hurt the others:

    minimise    1/2 y^T S y
    subject to  A y = b - A c,     lower - c <= y <= upper - c.

Each backend runs with a tolerance profile chosen so that a "solved" answer meets the
bounds to ~1e-8 (see ``shared/notes/qp_backends.md``) and with an iteration or time
limit; options given to the factory override the profile. Every answer is checked by
:func:`~.base.verify`; a backend exception never escapes (it becomes ERROR).
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import qpsolvers
import scipy.sparse as sp

from ..step.problem import StepProblem
from ._util import empty_box_failure
from .base import DEFAULT_TOLERANCE, Status, StepSolution, Tolerance, failed, verify
from .registry import register


@dataclass(frozen=True)
class Backend:
    """How to call one qpsolvers backend on the step QP.

    Attributes
    ----------
    solver : str
        qpsolvers name of the backend (``"proxqp"``, ...).
    extra : str
        The dualarm-qp pip extra that installs it.
    sparse : bool
        Pass csc matrices (faster through qpsolvers for osqp, proxqp, clarabel, highs).
    warm_start : bool
        The backend uses ``initvals``; ``problem.x_prev`` is then passed when given.
    profile : dict
        Default options: tolerances and the iteration / time limit.
    infeasible_when_not_found : bool
        The backend reports no solution only for inconsistent constraints (quadprog).
    """

    solver: str
    extra: str
    sparse: bool = False
    warm_start: bool = False
    profile: dict[str, Any] = field(default_factory=dict)
    infeasible_when_not_found: bool = False


#: Registry name suffix -> backend. Limits: iterations for every backend that has them,
#: plus a time limit [s] where the backend offers one. quadprog has no limit option: it
#: is a finite dual active-set method (at most a few n iterations on this problem).
#: Measured on 200 random 6 x 7 steps (s7 in 1e2..1e6): osqp's Ruiz scaling and
#: proxqp's preconditioner cause most of their failures here (osqp: 52 -> 2 misses,
#: proxqp: 11 -> 1 false "primal infeasible"), so both are switched off.
BACKENDS: dict[str, Backend] = {
    "osqp": Backend("osqp", "osqp", sparse=True, warm_start=True, profile={
        "eps_abs": 1e-7, "eps_rel": 0.0, "polishing": True, "scaling": 0, "max_iter": 4000,
        "time_limit": 0.1}),
    "proxsuite": Backend("proxqp", "proxsuite", sparse=True, warm_start=True, profile={
        "eps_abs": 1e-9, "eps_rel": 0.0, "compute_preconditioner": False, "max_iter": 1000}),
    "daqp": Backend("daqp", "daqp", profile={
        "primal_tol": 1e-10, "iter_limit": 1000, "time_limit": 0.1}),
    "clarabel": Backend("clarabel", "clarabel", sparse=True, profile={
        "tol_gap_abs": 1e-10, "tol_gap_rel": 1e-10, "tol_feas": 1e-10,
        "max_iter": 100, "time_limit": 0.1}),
    "piqp": Backend("piqp", "piqp", profile={
        "eps_abs": 1e-10, "eps_rel": 0.0, "max_iter": 100}),
    "highs": Backend("highs", "highs", sparse=True, profile={
        "primal_feasibility_tolerance": 1e-10, "dual_feasibility_tolerance": 1e-10,
        "time_limit": 0.1, "qp_iteration_limit": 1000}),
    "quadprog": Backend("quadprog", "quadprog", infeasible_when_not_found=True),
    "cvxopt": Backend("cvxopt", "cvxopt", profile={
        "abstol": 1e-10, "reltol": 1e-10, "feastol": 1e-10, "maxiters": 100}),
    "ecos": Backend("ecos", "ecos", profile={
        "abstol": 1e-10, "reltol": 1e-10, "feastol": 1e-10, "max_iters": 100}),
    "scs": Backend("scs", "scs", sparse=True, profile={
        "eps_abs": 1e-9, "eps_rel": 0.0, "max_iters": 100000, "time_limit_secs": 0.1}),
    "qpalm": Backend("qpalm", "qpalm", sparse=True, profile={
        "eps_abs": 1e-9, "eps_rel": 0.0, "max_iter": 10000, "max_time": 0.1}),
}


class QPSolver:
    """Solve the step QP with one qpsolvers backend.

    Parameters
    ----------
    backend : str
        Key of :data:`BACKENDS` (``"osqp"``, ``"proxsuite"``, ``"daqp"``, ...).
    tol : Tolerance
        Tolerances used by :func:`~.base.verify`.
    **options
        Backend options; they override the backend's profile (e.g. ``eps_abs=1e-6``).
    """

    def __init__(self, backend: str, *, tol: Tolerance = DEFAULT_TOLERANCE,
                 **options: Any) -> None:
        self.backend = BACKENDS[backend]
        self.name = f"qp:{backend}"
        self.tol = tol
        self.options = {**self.backend.profile, **options}

    def solve(self, problem: StepProblem) -> StepSolution:
        """Build the shifted QP, call the backend, and verify its answer."""
        start = time.perf_counter()
        empty = empty_box_failure(problem, self.name)
        if empty is not None:
            return empty
        c = problem.center
        P: np.ndarray | sp.csc_matrix = np.diag(problem.weights)
        A: np.ndarray | sp.csc_matrix = problem.A
        if self.backend.sparse:
            P, A = sp.csc_matrix(P), sp.csc_matrix(A)
        qp = qpsolvers.Problem(P, np.zeros(problem.n), A=A, b=problem.b - problem.A @ c,
                               lb=problem.lower - c, ub=problem.upper - c)
        initvals = None
        if self.backend.warm_start and problem.x_prev is not None:
            initvals = problem.x_prev - c
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                result = qpsolvers.solve_problem(qp, solver=self.backend.solver,
                                                 initvals=initvals, **self.options)
        except Exception as err:  # no backend exception may escape
            return failed(problem, Status.ERROR, self.name,
                          f"{self.backend.solver} raised {type(err).__name__}: {err}",
                          time.perf_counter() - start)
        elapsed = time.perf_counter() - start
        extras = {"backend_status": _status_text(result.extras)}
        if not result.found or result.x is None:
            text = extras["backend_status"]
            infeasible = self.backend.infeasible_when_not_found or "infeas" in text.lower()
            return failed(problem, Status.INFEASIBLE if infeasible else Status.ERROR,
                          self.name, f"{self.backend.solver} found no solution ({text})",
                          elapsed, **extras)
        x = np.asarray(result.x, dtype=np.float64) + c
        return verify(problem, StepSolution(x=x, status=Status.OPTIMAL, solver=self.name,
                                            solve_time=elapsed, extras=extras), self.tol)


def _status_text(extras: dict[str, Any]) -> str:
    """Backend status found in qpsolvers' ``Solution.extras``, as text ('' if none)."""
    if "status" in extras:
        return str(extras["status"])
    info = extras.get("info")
    for attr in ("status", "status_val"):
        if info is not None and hasattr(info, attr):
            return str(getattr(info, attr))
    return ""


def _register_all() -> None:
    """One registry entry per backend; available when qpsolvers can import it."""
    for key, backend in BACKENDS.items():
        def factory(*, _key: str = key, **options: Any) -> QPSolver:
            return QPSolver(_key, **options)

        register(f"qp:{key}", factory,
                 description=f"QP of Eq. 37 through qpsolvers/{backend.solver}",
                 available=backend.solver in qpsolvers.available_solvers,
                 extra=backend.extra, hard_bounds=True,
                 aliases=(f"qp:{backend.solver}",) if backend.solver != key else ())


_register_all()
