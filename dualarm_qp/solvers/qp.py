"""The step as a quadratic program, solved by any backend of qpsolvers (``qp:<backend>``).

The QP is written in the shifted variable ``y = x - c`` (Eq. 37 becomes ``y^T S y``
with no linear term), which measurably helps the interior-point backends (piqp,
clarabel) and does not hurt the others:

    minimise    1/2 y^T S y
    subject to  A y = b - A c,     lower - c <= y <= upper - c.

Each backend runs with a tolerance profile and an iteration or time limit; options
given to the factory override the profile. Every answer is checked by
:func:`~.base.verify`; a backend exception never escapes (it becomes ERROR).

Honesty: the status never rests on a backend's status text alone. An answer is OPTIMAL
only when it passes :func:`~.base.verify` (and, for iterative backends, preferably after
a KKT certificate, :func:`._kkt.refine`); a failed step is INFEASIBLE exactly when the
exact feasibility check :func:`._affine.max_task_scale` says so (the backend's own
verdict is kept in ``extras["backend_infeasible"]``), ERROR otherwise.

On the recorded step suite the sliding weight ``s7`` is 1e6..1e9 (the notes measured
1e2..1e6): the multipliers reach 1e5 and more, absolute dual tolerances such as
piqp's old ``eps_abs = 1e-10, eps_rel = 0`` cannot be met, and the first-order backends
(osqp, proxqp) ran into their iteration limits on many feasible steps. The backends
therefore see the cost divided by ``max(S)`` (same minimiser; see
:attr:`Backend.normalise_cost`), which removed nearly all of those misses.

A failure on a feasible step stays ERROR here; :func:`.policy.solve_step` can hand such
a step to a fallback solver.
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import sys
import time
import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import qpsolvers
import scipy.sparse as sp

from ..errors import InvalidInputError
from ..step.problem import StepProblem
from . import _native
from ._affine import max_task_scale
from ._kkt import refine
from ._util import empty_box_failure
from .base import (
    DEFAULT_TOLERANCE,
    Status,
    StepSolution,
    Tolerance,
    failed,
    verified_solution,
)
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
    exact : bool
        An active-set method whose "solved" was exact on the step suite (daqp, highs;
        not quadprog, which loses digits when ``s7`` reaches 1e9): its answer is refined
        only when it fails verification. The answers of the other backends are always
        refined first (see :class:`QPSolver`).
    normalise_cost : bool
        Divide the cost by ``max(S)`` (:func:`._native.cost_weights`; same minimiser).
        Measured on 2,000 random and 1,975 recorded clearly feasible steps, misses
        before -> after: proxqp 8.5% / 17.9% -> 2.2% / 0.5%, clarabel 1.2% / 2.3% -> 0,
        quadprog 13% / 14% -> 0, piqp 0 / 0.4% -> 0; highs 0 / 0 -> 0.2% / 0.4%, so
        highs keeps the raw cost. The native osqp and proxqp paths always normalise.
    """

    solver: str
    extra: str
    sparse: bool = False
    warm_start: bool = False
    profile: dict[str, Any] = field(default_factory=dict)
    infeasible_when_not_found: bool = False
    exact: bool = False
    normalise_cost: bool = True


#: Time limit [s] of one backend call where the backend takes one: a guard against a
#: runaway call (proxqp once took 49.6 s on one step), generous enough for a backend's
#: cold first call on a loaded machine (0.1 s was exceeded there).
TIME_LIMIT_S = 1.0

#: Registry name suffix -> backend. Limits: iterations for every backend that has them,
#: plus a time limit [s] where the backend offers one. quadprog has no limit option: it
#: is a finite dual active-set method (at most a few n iterations on this problem).
#: osqp's Ruiz scaling is off: on 200 random steps with the raw cost it caused most
#: misses (52 -> 2). With the cost normalised (:func:`._native.cost_weights`), measured on
#: 2,000 random and 1,975 recorded clearly feasible steps (misses random / recorded cold
#: / recorded warm-started):
#:
#: * proxqp: preconditioner back on and ``eps_primal_inf = 1e-12`` (its false "primal
#:   infeasible" verdicts go; the exact check decides infeasibility anyway):
#:   2.2% / 0.5% / 0.2% -> 0 / 0 / 0. ``max_iter`` counts outer iterations only; each
#:   ran up to ``max_iter_in`` = 1500 inner ones (1.6-13.6 s calls were seen); with
#:   200 x 100 the slowest call measured 0.05 s (infeasible steps included).
#: * osqp: ``adaptive_rho_interval = 25`` and ``max_iter = 10000`` (the time limit
#:   still holds): 0.25% / 0.46% / 0.1% -> 0.15% / 0.25% / 0.05%.
BACKENDS: dict[str, Backend] = {
    "osqp": Backend("osqp", "osqp", sparse=True, warm_start=True, profile={
        "eps_abs": 1e-7, "eps_rel": 0.0, "polishing": True, "scaling": 0,
        "adaptive_rho_interval": 25, "max_iter": 10000, "time_limit": TIME_LIMIT_S}),
    "proxsuite": Backend("proxqp", "proxsuite", sparse=True, warm_start=True, profile={
        "eps_abs": 1e-9, "eps_rel": 0.0, "eps_primal_inf": 1e-12,
        "compute_preconditioner": True, "max_iter": 200, "max_iter_in": 100}),
    "daqp": Backend("daqp", "daqp", exact=True, profile={
        "primal_tol": 1e-10, "iter_limit": 1000, "time_limit": TIME_LIMIT_S}),
    "clarabel": Backend("clarabel", "clarabel", sparse=True, profile={
        "max_iter": 100, "time_limit": TIME_LIMIT_S}),
    "piqp": Backend("piqp", "piqp", profile={
        "eps_abs": 1e-8, "eps_rel": 1e-9, "max_iter": 100}),
    "highs": Backend("highs", "highs", sparse=True, exact=True, normalise_cost=False,
                     profile={
        "primal_feasibility_tolerance": 1e-10, "dual_feasibility_tolerance": 1e-10,
        "time_limit": TIME_LIMIT_S, "qp_iteration_limit": 1000}),
    "quadprog": Backend("quadprog", "quadprog", infeasible_when_not_found=True),
    "cvxopt": Backend("cvxopt", "cvxopt", profile={
        "abstol": 1e-10, "reltol": 1e-10, "feastol": 1e-10, "maxiters": 100}),
    "ecos": Backend("ecos", "ecos", profile={
        "abstol": 1e-10, "reltol": 1e-10, "feastol": 1e-10, "max_iters": 100}),
    "scs": Backend("scs", "scs", sparse=True, profile={
        "eps_abs": 1e-9, "eps_rel": 0.0, "max_iters": 100000, "time_limit_secs": TIME_LIMIT_S}),
    "qpalm": Backend("qpalm", "qpalm", sparse=True, profile={
        "eps_abs": 1e-9, "eps_rel": 0.0, "max_iter": 10000, "max_time": TIME_LIMIT_S}),
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

    Notes
    -----
    osqp and proxsuite keep one native solver object per instance: while the problem's
    shape stays the same, each step only updates its data (``update``) and warm starts
    from ``problem.x_prev`` when it is given (a cold start otherwise). The other backends
    go through ``qpsolvers.solve_problem``.

    An iterative backend's answer (solved or not) is refined on the bounds it points to
    (:func:`._kkt.refine`: a KKT-certified optimum or nothing); without a certificate a
    "solved" answer is kept if it passes :func:`~.base.verify`. An exact backend's
    (``Backend.exact``) verified answer is taken as is, and refined only if it fails.
    Otherwise the step is INFEASIBLE when the exact feasibility check
    (:func:`._affine.max_task_scale`) says so, whatever the backend said, and ERROR when
    the step is feasible; the backend's own verdict is kept in ``extras``.
    """

    def __init__(self, backend: str, *, tol: Tolerance = DEFAULT_TOLERANCE,
                 **options: Any) -> None:
        self.backend = BACKENDS[backend]
        self.name = f"qp:{backend}"
        self.tol = tol
        self.options = {**self.backend.profile, **options}
        self._native: _native.NativeQP | None = None
        if self.backend.solver == "highs":
            _silence_highs_banner()
        if self.backend.solver in _native.NATIVE:
            self._native = _native.NATIVE[self.backend.solver](self.options)
        if options:
            self._check_options(options)

    def _check_options(self, options: dict[str, Any]) -> None:
        """Reject option names the backend does not know, now rather than at every step.

        One solve of a tiny problem with the options: a backend that refuses an option
        raises then (osqp, proxqp, daqp, ...). Raises InvalidInputError naming them.
        """
        probe = StepProblem(A=np.ones((1, 2)), b=np.ones(1), weights=np.ones(2),
                            center=np.zeros(2), lower=np.full(2, -10.0),
                            upper=np.full(2, 10.0), n_grasp=1)
        try:
            if self._native is not None:
                self._native.solve(probe)
            else:
                self._qpsolvers(probe)
        except (TypeError, ValueError, AttributeError, KeyError) as err:
            raise InvalidInputError(
                f"{self.name} does not accept the options {sorted(options)}: {err}"
            ) from None
        finally:
            if self._native is not None:
                self._native = _native.NATIVE[self.backend.solver](self.options)

    def solve(self, problem: StepProblem) -> StepSolution:
        """Build the shifted QP, call the backend, and verify its answer."""
        start = time.perf_counter()
        empty = empty_box_failure(problem, self.name)
        if empty is not None:
            return empty
        try:
            if self._native is not None:
                out = self._native.solve(problem)
            else:
                out = self._qpsolvers(problem)
        except Exception as err:  # no backend exception may escape
            return self._failure(problem, f"{self.backend.solver} raised "
                                 f"{type(err).__name__}: {err}", start, {}, False)
        extras: dict[str, Any] = {"backend_status": out.status}
        if out.iterations is not None:
            extras["iterations"] = out.iterations
        if out.x is not None and np.isfinite(out.x).all():
            x = out.x + problem.center
            if out.solved and self.backend.exact:
                sol = self._verified(problem, x, start, extras)
                if sol.status is Status.OPTIMAL:
                    return sol
            # The KKT certificate: an iterative backend's "solved" at its own tolerance
            # may be feasible yet off the optimum; the certified point is the optimum.
            refined = refine(problem, x)
            if refined is not None:
                sol = self._verified(problem, refined, start, {**extras, "refined": True})
                if sol.status is Status.OPTIMAL:
                    return sol
            if out.solved and not self.backend.exact:
                # Feasible, but no certificate: the point may be off the optimum (seen
                # up to 0.6 rad/s for quadprog at rank-deficient steps), so it is
                # reported FEASIBLE, never OPTIMAL.
                sol = self._verified(problem, x, start, {**extras, "certified": False},
                                     status=Status.FEASIBLE)
                if sol.status is Status.FEASIBLE:
                    return sol
        return self._failure(problem, f"{self.backend.solver}: {out.status or 'no status'}",
                             start, extras, out.infeasible)

    def _verified(self, problem: StepProblem, x: np.ndarray, start: float,
                  extras: dict[str, Any], status: Status = Status.OPTIMAL) -> StepSolution:
        # verified_solution is verify() without first building the unverified solution.
        return verified_solution(problem, x, status, solver=self.name, tol=self.tol,
                                 solve_time=time.perf_counter() - start, extras=extras)

    def _qpsolvers(self, problem: StepProblem) -> _native.BackendAnswer:
        """One call through ``qpsolvers.solve_problem`` (the backends without a native path)."""
        c = problem.center
        w = problem.weights
        P: np.ndarray | sp.csc_matrix = np.diag(
            _native.cost_weights(w) if self.backend.normalise_cost else w)
        A: np.ndarray | sp.csc_matrix = problem.A
        if self.backend.sparse:
            P, A = sp.csc_matrix(P), sp.csc_matrix(A)
        qp = qpsolvers.Problem(P, np.zeros(problem.n), A=A, b=problem.b - problem.A @ c,
                               lb=problem.lower - c, ub=problem.upper - c)
        initvals = None
        if self.backend.warm_start and problem.x_prev is not None:
            initvals = problem.x_prev - c
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                result = qpsolvers.solve_problem(qp, solver=self.backend.solver,
                                                 initvals=initvals, **self.options)
            except ValueError as err:
                if self.backend.infeasible_when_not_found:  # quadprog: "inconsistent"
                    return _native.BackendAnswer(None, False, True, str(err))
                raise
        text = _status_text(result.extras)
        x = None if result.x is None else np.asarray(result.x, dtype=np.float64)
        infeasible = _says_infeasible(self.backend.solver, text) or (
            self.backend.infeasible_when_not_found and not result.found)
        return _native.BackendAnswer(x, bool(result.found), infeasible, text)

    def _failure(self, problem: StepProblem, what: str, start: float,
                 extras: dict[str, Any], backend_infeasible: bool) -> StepSolution:
        """INFEASIBLE if the exact check finds no feasible point, ERROR otherwise."""
        extras = {**extras, "backend_infeasible": backend_infeasible}
        check = max_task_scale(problem, cap=1.0)
        if check.scale is None or check.scale < 1.0 - FEASIBLE_SCALE_TOL:
            extras["conflicts"] = check.blocking
            reach = "none" if check.scale is None else f"{check.scale:.6g}"
            return failed(problem, Status.INFEASIBLE, self.name,
                          f"{what}; infeasible by the exact check (largest task scale "
                          f"{reach}; blocking: {', '.join(check.blocking) or '-'})",
                          time.perf_counter() - start, **extras)
        note = " (the backend said infeasible, but it is not)" if backend_infeasible else ""
        return failed(problem, Status.ERROR, self.name,
                      f"{what}{note}; the step is feasible", time.perf_counter() - start,
                      **extras)


#: Task scale below ``1 - FEASIBLE_SCALE_TOL`` means the full task is out of reach.
FEASIBLE_SCALE_TOL = 1e-9

#: Status words by which a qpsolvers backend says the constraints are inconsistent.
_INFEASIBLE_WORDS: dict[str, tuple[str, ...]] = {
    "highs": ("kInfeasible",),
    "clarabel": ("PrimalInfeasible",),
    "piqp": ("PRIMAL_INFEASIBLE",),
    "qpalm": ("primal infeasible",),
    "scs": ("infeasible",),
}


_HIGHS_BANNER_DONE = False


def _silence_highs_banner() -> None:
    """Let HiGHS print its once-per-process banner into /dev/null.

    HiGHS (highspy 1.16) prints "Running HiGHS ... Copyright ..." from the constructor
    of its first instance in a process, before any option (``output_flag``,
    ``log_to_console``) can be set; later instances print nothing. One instance is
    built here with file descriptor 1 pointed at /dev/null, once per process. Whatever
    another thread writes to stdout in that moment (about a millisecond) is lost too.
    """
    global _HIGHS_BANNER_DONE
    if _HIGHS_BANNER_DONE:
        return
    _HIGHS_BANNER_DONE = True
    try:
        import highspy
    except ImportError:
        return
    with contextlib.suppress(OSError, ValueError, AttributeError):
        sys.stdout.flush()
        saved = os.dup(1)
        try:
            with open(os.devnull, "w") as null:
                os.dup2(null.fileno(), 1)
                try:
                    highspy.Highs()
                finally:
                    with contextlib.suppress(OSError, AttributeError, TypeError):
                        ctypes.CDLL(None).fflush(None)  # C stdio's buffer: to /dev/null
                    os.dup2(saved, 1)
        finally:
            os.close(saved)


def _says_infeasible(solver: str, text: str) -> bool:
    """Whether a qpsolvers backend's status text reports primal infeasibility."""
    return any(word.lower() in text.lower() for word in _INFEASIBLE_WORDS.get(solver, ()))


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
