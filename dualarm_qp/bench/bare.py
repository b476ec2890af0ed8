"""The bare solve time of a ``qp:*`` solver's backend, as qpsolvers times it."""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from .._signals import pass_on_sigint
from ..step.problem import StepProblem
from .interrupted import BackendInterrupted, backend_interrupted


class BareProbe:
    """Call a ``qp:*`` solver's backend through qpsolvers alone and read its solve time.

    The QP is built exactly as :class:`~dualarm_qp.solvers.qp.QPSolver` builds it (same
    shift, matrix format, options and warm start) outside the timed region; the time is
    the one qpsolvers measures around the backend's own call.
    """

    def __init__(self, solver: Any) -> None:
        self.solver = solver

    @classmethod
    def make(cls, solver: Any) -> BareProbe | None:
        """Return a probe of ``solver``, or None when it is not a ``qp:*`` solver."""
        if not str(getattr(solver, "name", "")).startswith("qp:"):
            return None
        if not (hasattr(solver, "backend") and hasattr(solver, "options")):
            return None
        return cls(solver)

    def solve_time(self, problem: StepProblem) -> float | None:
        """Return the backend's own solve time of ``problem`` [s], or None without one."""
        import qpsolvers
        import scipy.sparse as sp

        backend = self.solver.backend
        if problem.has_empty_box():
            return None
        c = problem.center
        P: Any = np.diag(problem.weights)
        A: Any = problem.A
        if backend.sparse:
            P, A = sp.csc_matrix(P), sp.csc_matrix(A)
        qp = qpsolvers.Problem(P, np.zeros(problem.n), A=A, b=problem.b - problem.A @ c,
                               lb=problem.lower - c, ub=problem.upper - c)
        initvals = None
        if backend.warm_start and problem.x_prev is not None:
            initvals = problem.x_prev - c
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                res = qpsolvers.solve_problem(qp, solver=backend.solver, initvals=initvals,
                                              **self.solver.options)
        except Exception as err:  # a backend failure is the solver's business, not the probe's
            if backend_interrupted(err):
                pass_on_sigint()
                raise BackendInterrupted(f"bare {backend.solver}: {err}") from None
            return None
        if backend_interrupted(probe_status(res)):
            # osqp's own SIGINT handler caught a Ctrl-C during the solve and qpsolvers does
            # not pass it on: hand it to Python (raises unless SIGINT is ignored).
            pass_on_sigint()
            raise BackendInterrupted(f"bare {backend.solver}: {probe_status(res)}")
        t = getattr(res, "solve_time", None)
        return float(t) if t is not None else None


def probe_status(res: Any) -> str:
    """Return a qpsolvers solution's backend status as text ('' if none)."""
    extras = getattr(res, "extras", None) or {}
    if "status" in extras:
        return str(extras["status"])
    info = extras.get("info")
    return str(getattr(info, "status", "")) if info is not None else ""


__all__ = ["BareProbe", "probe_status"]
