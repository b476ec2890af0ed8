"""The solver interface: a step problem goes in, a step solution comes out."""

from __future__ import annotations

import enum
import math
import operator
from dataclasses import dataclass, field, fields
from typing import Any, Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from ..step.problem import StepProblem

FloatArray = NDArray[np.float64]


class Status(str, enum.Enum):
    """Outcome of one step solve.

    OPTIMAL
        ``A x = b`` and the bounds hold within tolerance, and ``x`` minimises Eq. 37
        (for the reference solver: over the equality alone).
    FEASIBLE
        ``A x = b`` and the bounds hold within tolerance, but ``x`` is not claimed to
        minimise Eq. 37 (SNS; the fixed-grasp method, which holds ``m = 0``).
    SCALED
        The full task was infeasible; ``A x = scale * b`` holds while the bounds hold.
        Under the "scale" policy every solver gets the largest such ``scale`` in
        [0, 1] (:func:`~dualarm_qp.solvers.solve_step` finds it exactly).
    RELAXED
        The full task was infeasible; the equality was met in weighted least squares
        while the bounds hold.
    RECOVERING
        The state started outside a box; the solution never moves it further out and
        the range centres pull it back (set by the step builder, reported by the
        controller in place of OPTIMAL or FEASIBLE).
    ESCAPING
        The task scale collapsed at a singular configuration; the controller moves
        inside every bound to raise the arm's smallest singular value, the path held
        (:mod:`dualarm_qp.control.escape`). The equality holds to first order when the
        move lies in its null space, else within a share of the error budget.
    VIOLATION
        The solver returned a point that breaks a bound (or the equality) beyond
        tolerance. The reference method does this by design: it ignores the bounds.
    INFEASIBLE
        No point meets the equality and the bounds; ``x`` is not usable.
    ERROR
        The backend failed (exception, iteration or time limit).
    """

    OPTIMAL = "optimal"
    FEASIBLE = "feasible"
    SCALED = "scaled"
    RELAXED = "relaxed"
    RECOVERING = "recovering"
    ESCAPING = "escaping"
    VIOLATION = "violation"
    INFEASIBLE = "infeasible"
    ERROR = "error"

    @property
    def usable(self) -> bool:
        """Whether ``x`` may be integrated."""
        # Identity tests: ``in`` on a tuple compares str-enum members as strings, slowly.
        return (self is Status.OPTIMAL or self is Status.FEASIBLE or self is Status.SCALED
                or self is Status.RELAXED or self is Status.RECOVERING
                or self is Status.ESCAPING)


@dataclass(frozen=True)
class Tolerance:
    """Tolerances a solution must meet to be called a success.

    Parameters
    ----------
    equality : float
        Largest allowed ``|A x - scale * b|`` component [m/s or rad/s].
    bounds : float
        Largest allowed bound violation [rad/s or m/s].
    """

    equality: float = 1e-7
    bounds: float = 1e-7


DEFAULT_TOLERANCE = Tolerance()


@dataclass(frozen=True)
class StepSolution:
    """Result of solving one :class:`~dualarm_qp.step.StepProblem`.

    Attributes
    ----------
    x : ndarray, shape (n,)
        Joint rates [rad/s] and grasp sliding speeds [m/s]. NaN-free; all zeros when
        the status is not usable.
    status : Status
        What the solver claims (after verification, see :func:`verify`).
    objective : float
        Eq. 37 at ``x``.
    eq_residual : float
        ``max |A x - scale * b|``.
    bound_violation : float
        ``max(lower - x, x - upper, 0)``.
    active_lower, active_upper : ndarray of bool, shape (n,)
        Bounds active at ``x`` (within tolerance).
    scale : float
        Task scale applied (1.0 unless status is SCALED).
    solve_time : float
        Seconds spent in the solver.
    build_time : float
        Seconds spent building the problem (copied from the problem).
    solver : str
        Registry name of the solver.
    message : str
        Human-readable explanation for non-optimal outcomes.
    extras : dict
        Backend-specific details (iterations, backend status, ...).
    verified_with : Tolerance or None
        The tolerances :func:`verify` checked this solution against; None when it was
        never verified. Only :func:`verify` sets it: a caller holding a solution
        verified with its own tolerances need not verify it again.
    """

    x: FloatArray
    status: Status
    objective: float = float("nan")
    eq_residual: float = float("nan")
    bound_violation: float = float("nan")
    active_lower: NDArray[np.bool_] = field(default_factory=lambda: np.zeros(0, dtype=bool))
    active_upper: NDArray[np.bool_] = field(default_factory=lambda: np.zeros(0, dtype=bool))
    scale: float = 1.0
    solve_time: float = 0.0
    build_time: float = 0.0
    solver: str = ""
    message: str = ""
    extras: dict[str, Any] = field(default_factory=dict)
    verified_with: Tolerance | None = None

    @property
    def success(self) -> bool:
        """Whether ``x`` may be integrated (see :attr:`Status.usable`)."""
        return self.status.usable


@runtime_checkable
class StepSolver(Protocol):
    """What every solver in the registry provides.

    A solver is built once (with its options) and called once per step. It may keep
    state between calls (a factorisation, a warm start), but must give a correct
    answer for any problem handed to it.
    """

    name: str

    def solve(self, problem: StepProblem) -> StepSolution:
        """Solve one step problem and return a solution passed through :func:`verify`."""
        ...


def residuals(problem: StepProblem, x: FloatArray, scale: float = 1.0) -> tuple[float, float]:
    """Return ``(equality residual, bound violation)`` of ``x`` for ``problem``."""
    eq, viol, _ = _residuals(problem, x, x.tolist(), scale)
    return eq, viol


def _residuals(problem: StepProblem, x: FloatArray, xs: list[float], scale: float
               ) -> tuple[float, float, list[list[float]]]:
    """:func:`residuals`, and the signed bound gaps ``[lower - x, x - upper]``.

    ``xs`` is ``x.tolist()``. Python floats with C-level ``map``: at this size each
    numpy call costs more than the arithmetic.
    """
    eq = 0.0
    if problem.m:
        b = problem.b.tolist()
        if scale != 1.0:
            b = [scale * bi for bi in b]
        eq = max(map(abs, map(operator.sub, (problem.A @ x).tolist(), b)))
    gaps = [list(map(operator.sub, problem.lower.tolist(), xs)),
            list(map(operator.sub, xs, problem.upper.tolist()))]
    viol = max([0.0, *gaps[0], *gaps[1]])
    return eq, viol, gaps


def equality_limit(problem: StepProblem, tol: Tolerance) -> float:
    """Largest ``|A x - scale * b|`` component that counts as meeting the equality.

    ``tol.equality`` relative to ``max(1, max |b|)`` [m/s or rad/s].
    """
    return tol.equality * max(1.0, max(map(abs, problem.b.tolist()), default=0.0))


def verify(
    problem: StepProblem,
    solution: StepSolution,
    tol: Tolerance = DEFAULT_TOLERANCE,
    *,
    claims_bounds: bool = True,
) -> StepSolution:
    """Recompute the residuals of ``solution`` and downgrade a false claim.

    Parameters
    ----------
    problem : StepProblem
        The problem that was solved.
    solution : StepSolution
        What the solver returned.
    tol : Tolerance
        Tolerances for the equality and the bounds.
    claims_bounds : bool
        False for methods that ignore the bounds (the paper's reference step): their
        bound violations are still measured and reported as VIOLATION.

    Returns
    -------
    StepSolution
        A copy with residuals, objective and active sets filled in, and
        ``verified_with = tol``. A usable status whose residuals exceed ``tol`` becomes
        VIOLATION; a non-finite ``x`` becomes ERROR with ``x`` set to zero.
    """
    return verified_solution(
        problem, solution.x, solution.status, tol=tol, claims_bounds=claims_bounds,
        scale=solution.scale, solve_time=solution.solve_time, solver=solution.solver,
        message=solution.message, extras=solution.extras,
    )


def verified_solution(
    problem: StepProblem,
    x: FloatArray,
    status: Status,
    *,
    solver: str,
    tol: Tolerance = DEFAULT_TOLERANCE,
    claims_bounds: bool = True,
    scale: float = 1.0,
    solve_time: float = 0.0,
    message: str = "",
    extras: dict[str, Any] | None = None,
) -> StepSolution:
    """Verify a solver's answer ``x`` with the ``status`` it claims; what solvers return.

    Equal to ``verify(problem, StepSolution(x=x, status=status, ...), tol)`` (the
    keywords are the :class:`StepSolution` fields of the same names), without building
    the unverified solution first.
    """
    n = problem.n
    extras = {} if extras is None else extras
    xs: list[float] = x.tolist() if isinstance(x, np.ndarray) and x.shape == (n,) else []
    # A finite sum is the cheap common case (NaN and inf propagate through it).
    if len(xs) != n or (not math.isfinite(sum(xs)) and not np.isfinite(x).all()):
        return _solution(
            x=np.zeros(n), status=Status.ERROR if status.usable else status,
            objective=math.nan, eq_residual=math.nan, bound_violation=math.nan,
            active_lower=np.zeros(n, dtype=bool), active_upper=np.zeros(n, dtype=bool),
            scale=scale, solve_time=solve_time, build_time=problem.build_time,
            solver=solver, message=message or "solver returned a non-finite or misshaped x",
            extras=extras, verified_with=tol,
        )
    eq, viol, gaps = _residuals(problem, x, xs, scale)
    if status.usable:
        scale_eq = equality_limit(problem, tol)
        if status is not Status.RELAXED and status is not Status.ESCAPING and eq > scale_eq:
            status = Status.VIOLATION
            message = message or f"equality residual {eq:.3g} exceeds tolerance {scale_eq:.3g}"
        if viol > tol.bounds:
            status = Status.VIOLATION
            worst = int(np.argmax(np.maximum(problem.lower - x, x - problem.upper)))
            message = message or (
                f"{problem.names[worst]} = {x[worst]:.6g} outside "
                f"[{problem.lower[worst]:.6g}, {problem.upper[worst]:.6g}]"
                + ("" if claims_bounds else " (this method ignores the bounds)")
            )
    # A bound is active when x is within act_tol of it (or beyond): its gap >= -act_tol.
    active = np.array(gaps) >= -max(tol.bounds, 1e-9)
    return _solution(
        x=x, status=status, objective=problem.objective(x), eq_residual=eq,
        bound_violation=viol, active_lower=active[0], active_upper=active[1], scale=scale,
        solve_time=solve_time, build_time=problem.build_time, solver=solver,
        message=message, extras=extras, verified_with=tol,
    )


_SOLUTION_FIELDS = frozenset(f.name for f in fields(StepSolution))


def _solution(**values: Any) -> StepSolution:
    """``StepSolution(**values)`` for values of every field, built at once.

    The frozen dataclass's ``__init__`` sets its 14 fields one ``object.__setattr__``
    call at a time, which costs more than a fast solve's arithmetic. The class has no
    ``__post_init__`` and no slots, so filling ``__dict__`` gives the same object.
    """
    if values.keys() != _SOLUTION_FIELDS:
        raise TypeError(f"StepSolution fields missing or unknown: "
                        f"{sorted(_SOLUTION_FIELDS.symmetric_difference(values))}")
    solution = object.__new__(StepSolution)
    solution.__dict__.update(values)
    return solution


def failed(problem: StepProblem, status: Status, solver: str, message: str,
           solve_time: float = 0.0, **extras: Any) -> StepSolution:
    """Return a solution carrying no usable ``x`` (zeros), with its reason."""
    n = problem.n
    return StepSolution(
        x=np.zeros(n),
        status=status,
        solver=solver,
        message=message,
        solve_time=solve_time,
        build_time=problem.build_time,
        active_lower=np.zeros(n, dtype=bool),
        active_upper=np.zeros(n, dtype=bool),
        extras=dict(extras),
    )
