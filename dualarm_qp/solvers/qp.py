"""The step as a quadratic program, solved by any backend of qpsolvers (``qp:<backend>``).

The QP is written in the shifted variable ``y = x - c`` (Eq. 37 becomes ``y^T S y``
with no linear term), which measurably helps the interior-point backends (piqp,
clarabel) and does not hurt the others:

    minimise    1/2 y^T W y
    subject to  A y = b - A c,   G y <= h - G c,   lower - c <= y <= upper - c.

General rows go to the backend natively. Each backend (one module of
:mod:`.backends`) runs with a tolerance profile and an iteration or time limit; options
given to the factory override the profile (:mod:`.qp_options`). A backend exception
never escapes (it becomes ERROR).

Honesty: the status never rests on a backend's status text alone. The backend's point
is refined on the limits it points to (:func:`._kkt.refine`: an exact, KKT-certified
optimum or nothing) and claimed OPTIMAL only then; a "solved" point without that
certificate is claimed FEASIBLE; every claim is then checked by
:func:`~.certify.certify`. A failed step is INFEASIBLE exactly when the exact
feasibility check :func:`._scale.max_task_scale` says so (the backend's own verdict is
kept in ``extras["backend_infeasible"]``), ERROR otherwise.

On the recorded step suite the sliding weight ``s7`` is 1e6..1e9 (the notes measured
1e2..1e6): the multipliers reach 1e5 and more, absolute dual tolerances such as
piqp's old ``eps_abs = 1e-10, eps_rel = 0`` cannot be met, and the first-order backends
(osqp, proxqp) ran into their iteration limits on many feasible steps. The backends
therefore see the cost divided by ``max(S)`` (same minimiser; see
:attr:`.backends.base.Backend.normalise_cost`), which removed nearly all of those misses.

A failure on a feasible step stays ERROR here; :func:`.policy.solve_step` can hand such
a step to a fallback solver.
"""

from __future__ import annotations

import functools
import time
from typing import Any

import numpy as np

from ..errors import InvalidInputError
from ..step.problem import StepProblem
from ._kkt import refine
from ._scale import max_task_scale
from ._util import empty_box_failure
from .backends import (
    BACKENDS,
    NATIVE,
    TIME_LIMIT_S,
    BackendAnswer,
    NativeQP,
    installed,
    solve_with_qpsolvers,
)
from .base import DEFAULT_TOLERANCE, Status, StepSolution, Tolerance, failed
from .qp_options import backend_options, check_backend_options, quiet_output
from .registry import SolverOptionError, check_tolerance, register


class QPSolver:
    """Solve the step QP with one qpsolvers backend.

    Parameters
    ----------
    backend : str
        Key of :data:`BACKENDS` (``"osqp"``, ``"proxsuite"``, ``"daqp"``, ...).
    tol : Tolerance
        Tolerances used by :func:`~.certify.certify`.
    **options
        Backend options; they override the backend's profile (e.g. ``eps_abs=1e-6``).

    Notes
    -----
    osqp and proxsuite keep one native solver object per instance: while the problem's
    shape stays the same, each step only updates its data (``update``) and warm starts
    from ``problem.x_prev`` when it is given (a cold start otherwise). The other backends
    go through ``qpsolvers.solve_problem``.

    Every backend's answer (solved or not) is refined on the bounds it points to
    (:func:`._kkt.refine`: a KKT-certified optimum or nothing) and is OPTIMAL only when
    certified; without a certificate a "solved" answer that passes
    :func:`~.certify.certify` is FEASIBLE (the active-set backends are no exception: highs
    called 622 of 5,536 recorded steps solved up to 2.5e-6 off the optimum). Otherwise
    the step is INFEASIBLE when the exact feasibility check
    (:func:`._scale.max_task_scale`) says so, whatever the backend said, and ERROR when
    the step is feasible; the backend's own verdict is kept in ``extras``.
    """

    def __init__(self, backend: str, *, tol: Tolerance = DEFAULT_TOLERANCE,
                 **options: Any) -> None:
        self.backend = BACKENDS[backend]
        self.name = f"qp:{backend}"
        check_tolerance(self.name, tol)
        self.tol = tol
        if self.backend.prepare is not None:
            self.backend.prepare()
        options = check_backend_options(self.name, self.backend.solver, options)
        self.options = {**self.backend.profile, **options}
        self._native: NativeQP | None = None
        if self.backend.solver in NATIVE:
            self._native = NATIVE[self.backend.solver](self.options)
        if options:
            # The backend judges a set of options once per process: a probe solve.
            key = (self.name, tuple(sorted((k, repr(v)) for k, v in options.items())))
            if key not in _JUDGED:
                self._check_options(options)
                _JUDGED.add(key)

    def _check_options(self, options: dict[str, Any]) -> None:
        """Let the backend itself judge the (already type-checked) options, once.

        Names, types and the usual ranges were checked by :func:`check_backend_options`;
        what remains is the backend's own rules (osqp's ``0 < alpha < 2``, ...). One solve
        of a tiny problem with the options: a backend that refuses a value raises then.
        The culprit is found by probing the options one at a time; raises
        SolverOptionError naming it (InvalidInputError if no single option is to blame).
        """
        err = self._probe(self.options)
        if err is None:
            return
        for key in options:
            if self._probe({**self.backend.profile, key: options[key]}) is not None:
                raise SolverOptionError(self.name, key, f"{self.backend.solver} refuses the "
                                        f"value {options[key]!r} ({err})") from None
        raise InvalidInputError(f"{self.name} does not accept the options "
                                f"{sorted(options)} together: {err}")

    def _probe(self, options: dict[str, Any]) -> str | None:
        """Solve a tiny step with ``options``; the backend's complaint, or None."""
        probe = StepProblem(A=np.ones((1, 2)), b=np.ones(1), weights=np.ones(2),
                            center=np.zeros(2), lower=np.full(2, -10.0),
                            upper=np.full(2, 10.0), n_grasp=1)
        saved, self.options = self.options, options
        native = self._native
        try:
            with quiet_output():
                if native is not None:
                    self._native = NATIVE[self.backend.solver](options)
                    self._native.solve(probe)
                else:
                    self._qpsolvers(probe)
        except Exception as err:  # any refusal by the backend (osqp: OSQPException)
            return f"{type(err).__name__}: {err}"
        finally:
            self.options = saved
            if native is not None:
                self._native = NATIVE[self.backend.solver](saved)
        return None

    def solve(self, problem: StepProblem) -> StepSolution:
        """Build the shifted QP, call the backend, and claim its (refined) answer."""
        start = time.perf_counter()
        empty = empty_box_failure(problem, self.name)
        if empty is not None:
            return empty
        try:
            if self._native is not None and problem.diagonal_cost:
                out = self._native.solve(problem)
            else:
                out = self._qpsolvers(problem)
        except Exception as err:  # no backend exception may escape
            return self._failure(problem, f"{self.backend.solver} raised "
                                 f"{type(err).__name__}: {err}", start, {}, False)
        extras: dict[str, Any] = {"backend_status": out.status}
        if out.iterations is not None:
            extras["iterations"] = out.iterations
        x = out.x  # the backend's point y, shifted back: y + c
        if x is not None and out.y is not None and np.isfinite(out.y).all():
            # The KKT certificate: a backend's "solved" at its own tolerance may be
            # feasible yet off the optimum; the certified point is the optimum.
            refined = refine(problem, x)
            if refined is not None:  # feasible and KKT-certified: the optimum
                return self._claim(Status.OPTIMAL, refined, start,
                                   {**extras, "refined": True})
            if out.solved:
                # Solved, but no certificate: the point may be off the optimum (seen
                # up to 0.6 rad/s for quadprog at rank-deficient steps), so it is
                # claimed FEASIBLE, never OPTIMAL (the certificate checks the claim).
                return self._claim(Status.FEASIBLE, x, start,
                                   {**extras, "certified": False,
                                    "primal_residual": out.primal_residual()})
        return self._failure(problem, f"{self.backend.solver}: {out.status or 'no status'}",
                             start, extras, out.infeasible)

    def _claim(self, status: Status, x: np.ndarray, start: float, extras: dict[str, Any]
               ) -> StepSolution:
        return StepSolution(x=x, status=status, solver=self.name,
                            solve_time=time.perf_counter() - start, extras=extras)

    def _qpsolvers(self, problem: StepProblem) -> BackendAnswer:
        """One call through ``qpsolvers.solve_problem`` (the backends without a native path)."""
        return solve_with_qpsolvers(self.backend, problem, self.options)

    def _failure(self, problem: StepProblem, what: str, start: float,
                 extras: dict[str, Any], backend_infeasible: bool) -> StepSolution:
        """INFEASIBLE if the exact check finds no feasible point, ERROR otherwise."""
        extras = {**extras, "backend_infeasible": backend_infeasible}
        check = max_task_scale(problem, cap=1.0)
        if not check.full:
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


#: Option sets a backend has accepted in this process (see ``QPSolver.__init__``).
_JUDGED: set[tuple[str, tuple[tuple[str, str], ...]]] = set()


def _qp_solver(key: str, /, **options: Any) -> QPSolver:
    """Return a solver of backend ``key``: the registry's factory (module-level: it pickles)."""
    return QPSolver(key, **options)


def _register_all() -> None:
    """One registry entry per backend; available when qpsolvers can import it."""
    for key, backend in BACKENDS.items():
        register(f"qp:{key}", functools.partial(_qp_solver, key),
                 description=f"QP of Eq. 37 through qpsolvers/{backend.solver}",
                 available=functools.partial(installed, backend.solver),
                 extra=backend.extra, hard_bounds=True,
                 aliases=(f"qp:{backend.solver}",) if backend.solver != key else ())


_register_all()

__all__ = ["BACKENDS", "TIME_LIMIT_S", "QPSolver", "backend_options", "check_backend_options"]
