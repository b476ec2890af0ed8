"""The step as a quadratic program, solved by any backend of qpsolvers (``qp:<backend>``).

The QP is written in the shifted variable ``y = x - c`` (Eq. 37 becomes ``y^T S y``
with no linear term), which measurably helps the interior-point backends (piqp,
clarabel) and does not hurt the others:

    minimise    1/2 y^T W y
    subject to  A y = b - A c,   G y <= h - G c,   lower - c <= y <= upper - c.

General rows go to the backend natively. Each backend runs with a tolerance profile and
an iteration or time limit; options given to the factory override the profile. A
backend exception never escapes (it becomes ERROR).

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
:attr:`Backend.normalise_cost`), which removed nearly all of those misses.

A failure on a feasible step stays ERROR here; :func:`.policy.solve_step` can hand such
a step to a fallback solver.
"""

from __future__ import annotations

import contextlib
import ctypes
import enum
import functools
import inspect
import math
import os
import sys
import time
import warnings
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import InvalidInputError
from ..step.problem import StepProblem
from . import _native
from ._kkt import refine
from ._scale import max_task_scale
from ._util import empty_box_failure
from .base import DEFAULT_TOLERANCE, Status, StepSolution, Tolerance, failed
from .registry import SolverOptionError, check_tolerance, register

if TYPE_CHECKING:
    import scipy.sparse as sp


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
    "daqp": Backend("daqp", "daqp", profile={
        "primal_tol": 1e-10, "iter_limit": 1000, "time_limit": TIME_LIMIT_S}),
    "clarabel": Backend("clarabel", "clarabel", sparse=True, profile={
        "max_iter": 100, "time_limit": TIME_LIMIT_S}),
    "piqp": Backend("piqp", "piqp", profile={
        "eps_abs": 1e-8, "eps_rel": 1e-9, "max_iter": 100}),
    "highs": Backend("highs", "highs", sparse=True, normalise_cost=False,
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
    (:func:`._affine.max_task_scale`) says so, whatever the backend said, and ERROR when
    the step is feasible; the backend's own verdict is kept in ``extras``.
    """

    def __init__(self, backend: str, *, tol: Tolerance = DEFAULT_TOLERANCE,
                 **options: Any) -> None:
        self.backend = BACKENDS[backend]
        self.name = f"qp:{backend}"
        check_tolerance(self.name, tol)
        self.tol = tol
        if self.backend.solver == "highs":
            _silence_highs_banner()
        options = check_backend_options(self.name, self.backend.solver, options)
        self.options = {**self.backend.profile, **options}
        self._native: _native.NativeQP | None = None
        if self.backend.solver in _native.NATIVE:
            self._native = _native.NATIVE[self.backend.solver](self.options)
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
            with _quiet_output():
                if native is not None:
                    self._native = _native.NATIVE[self.backend.solver](options)
                    self._native.solve(probe)
                else:
                    self._qpsolvers(probe)
        except Exception as err:  # any refusal by the backend (osqp: OSQPException)
            return f"{type(err).__name__}: {err}"
        finally:
            self.options = saved
            if native is not None:
                self._native = _native.NATIVE[self.backend.solver](saved)
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
        if out.x is not None and np.isfinite(out.x).all():
            x = out.x + problem.center
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
                return self._claim(Status.FEASIBLE, x, start, {**extras, "certified": False})
        return self._failure(problem, f"{self.backend.solver}: {out.status or 'no status'}",
                             start, extras, out.infeasible)

    def _claim(self, status: Status, x: np.ndarray, start: float, extras: dict[str, Any]
               ) -> StepSolution:
        return StepSolution(x=x, status=status, solver=self.name,
                            solve_time=time.perf_counter() - start, extras=extras)

    def _qpsolvers(self, problem: StepProblem) -> _native.BackendAnswer:
        """One call through ``qpsolvers.solve_problem`` (the backends without a native path)."""
        import qpsolvers
        c = problem.center
        P: np.ndarray | sp.csc_matrix = (_native.cost_matrix(problem.weights)
                                         if self.backend.normalise_cost
                                         else problem.weight_matrix())
        A: np.ndarray | sp.csc_matrix = problem.A
        G: np.ndarray | sp.csc_matrix | None = None
        h = None
        if problem.p:
            G, h = _native.shifted_rows(problem)
        if self.backend.sparse:
            import scipy.sparse as sp  # with a sparse backend only (0.2 s to import)

            P, A = sp.csc_matrix(P), sp.csc_matrix(A)
            G = None if G is None else sp.csc_matrix(G)
        qp = qpsolvers.Problem(P, np.zeros(problem.n), G=G, h=h, A=A,
                               b=problem.b - problem.A @ c,
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

#: Options that dualarm-qp sets itself on every backend (output stays silent).
_MANAGED_OPTIONS = frozenset({"verbose"})

#: Data arguments of ``daqp.solve`` (not options).
_DAQP_DATA = frozenset({"H", "f", "A", "bupper", "blower", "sense", "break_points", "is_avi",
                        "primal_start", "dual_start"})

#: Iteration limits that must be at least 1 (0 iterations never solves a step).
_ITERATION_LIMITS = frozenset({"max_iter", "max_iters", "maxiters", "iter_limit",
                               "qp_iteration_limit", "max_iter_in"})


@dataclass(frozen=True)
class OptionType:
    """Type of one backend option, read from the installed backend.

    Attributes
    ----------
    kind : str
        ``"bool"``, ``"int"``, ``"float"`` or ``"str"``.
    default : object
        The backend's default (decides the sign rule of tolerances).
    flag : bool
        An integer used as a switch (0 / 1): true and false are accepted too.
    choices : tuple, optional
        The values accepted, when only a few are.
    """

    kind: str
    default: Any = None
    flag: bool = False
    choices: tuple[Any, ...] | None = None


def _kind(value: Any) -> str | None:
    if isinstance(value, bool):
        return "bool"
    if isinstance(value, int) and not isinstance(value, enum.Enum):
        return "int"
    if isinstance(value, float):
        return "float"
    if isinstance(value, str):
        return "str"
    return None  # enums, lists, methods: not settable from a file


def _from_attributes(obj: Any) -> dict[str, OptionType]:
    out: dict[str, OptionType] = {}
    for name in dir(obj):
        if name.startswith("_") or name in _MANAGED_OPTIONS:
            continue
        try:
            value = getattr(obj, name)
        except Exception:  # a property that cannot be read is no option
            continue
        if callable(value) and not isinstance(value, (int, float, str)):
            continue
        kind = _kind(value)
        if kind is not None:
            out[name] = OptionType(kind, value, flag=kind == "int" and value in (0, 1))
    return out


@functools.cache
def backend_options(solver: str) -> dict[str, OptionType] | None:
    """Option names and types of a qpsolvers backend, read from the installed package.

    osqp: the fields of its ``OSQPSettings`` (plus ``solver_type`` and
    ``cg_preconditioner``, which its wrapper translates); proxqp: the attributes of
    ``proxqp.dense.QP(...).settings``; daqp: the keywords of ``daqp.solve``; piqp: the
    attributes of ``DenseSolver().settings``; clarabel: those of ``DefaultSettings()``;
    highs: every name ``Highs.getOptionType`` knows (the value is then checked by
    ``setOptionValue``); quadprog: none. Enum-valued settings, which a file cannot give,
    and ``verbose`` (dualarm-qp keeps the backends silent) are left out. None for a
    backend that is not installed here or has no known list.
    """
    try:
        if solver == "osqp":
            import osqp

            ext = osqp.OSQP().ext
            settings = ext.OSQPSettings()
            ext.osqp_set_default_settings(settings)
            out = _from_attributes(settings)
            out["solver_type"] = OptionType("str", "direct", choices=("direct", "indirect"))
            out["cg_preconditioner"] = OptionType("str", "diagonal",
                                                  choices=("diagonal", None))
            return out
        if solver == "proxqp":
            from proxsuite import proxqp

            return _from_attributes(proxqp.dense.QP(1, 0, 0, True).settings)
        if solver == "daqp":
            import daqp

            params = inspect.signature(daqp.solve).parameters
            return {name: OptionType(kind, p.default, flag=False)
                    for name, p in params.items()
                    if name not in _DAQP_DATA and (kind := _kind(p.default)) is not None}
        if solver == "piqp":
            import piqp

            return _from_attributes(piqp.DenseSolver().settings)
        if solver == "clarabel":
            import clarabel

            return _from_attributes(clarabel.DefaultSettings())
        if solver == "highs":
            import highspy

            h = _quiet_highs()
            kinds = {highspy.HighsOptionType.kBool: "bool",
                     highspy.HighsOptionType.kInt: "int",
                     highspy.HighsOptionType.kDouble: "float",
                     highspy.HighsOptionType.kString: "str"}
            out = {}
            for name in dir(highspy.HighsOptions()):
                if name.startswith("_") or name in _MANAGED_OPTIONS:
                    continue
                status, kind = h.getOptionType(name)
                if status == highspy.HighsStatus.kOk and kind in kinds:
                    out[name] = OptionType(kinds[kind], h.getOptionValue(name)[1])
            return out
        if solver == "quadprog":
            return {}
    except ImportError:
        return None
    return None


@contextlib.contextmanager
def _quiet_output() -> Any:
    """Send what C code prints to file descriptors 1 and 2 to /dev/null meanwhile.

    osqp prints "ERROR in validate_settings ..." from C when it refuses a setting; the
    refusal is reported as one SolverOptionError instead.
    """
    saved: list[int] = []
    try:
        sys.stdout.flush()
        sys.stderr.flush()
        with open(os.devnull, "w") as null:
            for fd in (1, 2):
                saved.append(os.dup(fd))
                os.dup2(null.fileno(), fd)
    except (OSError, ValueError, AttributeError):
        pass  # no real descriptors (an embedded interpreter): let it print
    try:
        yield
    finally:
        with contextlib.suppress(OSError, AttributeError, TypeError):
            ctypes.CDLL(None).fflush(None)
        for fd, copy in zip((1, 2), saved, strict=False):
            os.dup2(copy, fd)
            os.close(copy)


def _quiet_highs() -> Any:
    """Return a HiGHS instance that prints nothing, for checking option names and values."""
    import highspy

    _silence_highs_banner()
    h = highspy.Highs()
    h.setOptionValue("output_flag", False)
    return h


def check_backend_options(name: str, solver: str, options: dict[str, Any]) -> dict[str, Any]:
    """Check option names, types and the usual ranges against the installed backend.

    Rules beyond the type: every number is finite (an infinite time limit or bound is
    allowed), integers are >= 0, iteration limits (``max_iter``, ``iter_limit``, ...)
    are >= 1, and tolerances (names with ``eps`` or ``tol``) are >= 0 unless the
    backend's default is negative. A HiGHS value is also checked by HiGHS itself
    (``setOptionValue``). An integer given for a real option becomes a float.

    Parameters
    ----------
    name : str
        Registry name (``"qp:osqp"``), for the messages.
    solver : str
        qpsolvers backend name.
    options : dict
        The options given.

    Returns
    -------
    dict
        The options, integers for real options converted to float.

    Raises
    ------
    SolverOptionError
        Naming the option: an unknown name (with the valid names), a wrong type (with
        the expected type) or a value out of range.
    """
    known = backend_options(solver)
    out: dict[str, Any] = {}
    for key, value in options.items():
        if key in _MANAGED_OPTIONS:
            raise SolverOptionError(name, key, "set by dualarm-qp (the backends run "
                                    "silently); leave it out")
        if known is None:
            out[key] = value
            continue
        if key not in known:
            raise SolverOptionError(name, key, "unknown option",
                                    valid=sorted(known) or [f"none: {solver} takes no options"])
        out[key] = _check_value(name, key, value, known[key])
    if solver == "highs" and out:
        _check_highs_values(name, out)
    return out


def _check_value(name: str, key: str, value: Any, spec: OptionType) -> Any:
    """One option's value against its type and the range rules of check_backend_options."""
    def refuse(what: str) -> SolverOptionError:
        return SolverOptionError(name, key, what)

    if spec.choices is not None:
        if value not in spec.choices:
            raise SolverOptionError(name, key, f"invalid value {value!r}",
                                    valid=[str(c).lower() if c is None else str(c)
                                           for c in spec.choices])
        return value
    if spec.kind == "bool":
        if not isinstance(value, bool):
            raise refuse(f"expected true or false, got {value!r}")
        return value
    if spec.kind == "str":
        if not isinstance(value, str):
            raise refuse(f"expected text, got {value!r}")
        return value
    if isinstance(value, bool):
        if spec.kind == "int" and spec.flag:
            return int(value)
        raise refuse(f"expected {'an integer' if spec.kind == 'int' else 'a number'}, "
                     f"got {str(value).lower()}")
    if spec.kind == "int":
        if not isinstance(value, int):
            raise refuse(f"expected an integer, got {value!r}")
        low = 1 if key in _ITERATION_LIMITS else 0
        if value < low:
            raise refuse(f"must be >= {low}, got {value}")
        return value
    if not isinstance(value, (int, float)):
        raise refuse(f"expected a number, got {value!r}")
    number = float(value)
    if math.isnan(number) or (math.isinf(number) and not any(
            w in key for w in ("limit", "bound", "infinite", "max_time"))):
        raise refuse(f"expected a finite number, got {value!r}")
    default = spec.default if isinstance(spec.default, (int, float)) else 0.0
    if ("tol" in key or "eps" in key or "time" in key) and default >= 0 and number < 0:
        raise refuse(f"must be >= 0, got {value!r}")
    return number


def _check_highs_values(name: str, options: dict[str, Any]) -> None:
    """HiGHS's own check of each value (range, type), through a silent instance."""
    import highspy

    h = _quiet_highs()
    for key, value in options.items():
        if h.setOptionValue(key, value) != highspy.HighsStatus.kOk:
            raise SolverOptionError(name, key, f"HiGHS refuses the value {value!r} (out of "
                                    "its range or of the wrong type)")



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


def _installed(solver: str) -> bool:
    """Whether qpsolvers can import the backend ``solver``.

    qpsolvers imports every installed backend when it is imported (a tenth of a second
    or more): it is imported when a solver's availability is first asked, or a
    ``qp:*`` solver runs, not with this module.
    """
    import qpsolvers

    return solver in qpsolvers.available_solvers


def _qp_solver(key: str, /, **options: Any) -> QPSolver:
    """Return a solver of backend ``key``: the registry's factory (module-level: it pickles)."""
    return QPSolver(key, **options)


def _register_all() -> None:
    """One registry entry per backend; available when qpsolvers can import it."""
    for key, backend in BACKENDS.items():
        register(f"qp:{key}", functools.partial(_qp_solver, key),
                 description=f"QP of Eq. 37 through qpsolvers/{backend.solver}",
                 available=functools.partial(_installed, backend.solver),
                 extra=backend.extra, hard_bounds=True,
                 aliases=(f"qp:{backend.solver}",) if backend.solver != key else ())


_register_all()
