"""The solver interface: a step problem goes in, a step solution comes out."""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass, field, replace
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
    SCALED
        The full task was infeasible; ``A x = scale * b`` holds with the largest
        ``scale`` in [0, 1] for which the bounds can be met.
    RELAXED
        The full task was infeasible; the equality was met in weighted least squares
        while the bounds hold.
    RECOVERING
        The state started outside a box; the solution moves it back toward the box at
        a bounded rate (set by the step builder, reported by the controller).
    VIOLATION
        The solver returned a point that breaks a bound (or the equality) beyond
        tolerance. The reference method does this by design: it ignores the bounds.
    INFEASIBLE
        No point meets the equality and the bounds; ``x`` is not usable.
    ERROR
        The backend failed (exception, iteration or time limit).
    """

    OPTIMAL = "optimal"
    SCALED = "scaled"
    RELAXED = "relaxed"
    RECOVERING = "recovering"
    VIOLATION = "violation"
    INFEASIBLE = "infeasible"
    ERROR = "error"

    @property
    def usable(self) -> bool:
        """Whether ``x`` may be integrated."""
        return self in (Status.OPTIMAL, Status.SCALED, Status.RELAXED, Status.RECOVERING)


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
        """Solve one step problem and return a verified solution."""
        ...


def residuals(problem: StepProblem, x: FloatArray, scale: float = 1.0) -> tuple[float, float]:
    """Return ``(equality residual, bound violation)`` of ``x`` for ``problem``."""
    # Python max over .tolist(): a numpy reduction costs microseconds at this size.
    eq = 0.0
    if problem.m:
        r = problem.A @ x
        r -= problem.b if scale == 1.0 else scale * problem.b
        rs = r.tolist()
        eq = max(max(rs), -min(rs))
    viol = max(0.0, max(np.maximum(problem.lower - x, x - problem.upper).tolist()))
    return eq, viol


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
        A copy with residuals, objective and active sets filled in. A usable status
        whose residuals exceed ``tol`` becomes VIOLATION; a non-finite ``x`` becomes
        ERROR with ``x`` set to zero.
    """
    x = solution.x
    n = problem.n
    # A finite sum is the cheap common case (NaN and inf propagate through it).
    if x.shape != (n,) or (not math.isfinite(sum(x.tolist())) and not np.isfinite(x).all()):
        return replace(
            solution,
            x=np.zeros(n),
            status=Status.ERROR if solution.status.usable else solution.status,
            message=solution.message or "solver returned a non-finite or misshaped x",
            build_time=problem.build_time,
            active_lower=np.zeros(n, dtype=bool),
            active_upper=np.zeros(n, dtype=bool),
        )
    eq, viol = residuals(problem, x, solution.scale)
    status = solution.status
    message = solution.message
    scale_eq = tol.equality * max(1.0, max(map(abs, problem.b.tolist()), default=0.0))
    if status.usable and status is not Status.RELAXED and eq > scale_eq:
        status = Status.VIOLATION
        message = message or f"equality residual {eq:.3g} exceeds tolerance {scale_eq:.3g}"
    if status.usable and viol > tol.bounds:
        status = Status.VIOLATION
        worst = int(np.argmax(np.maximum(problem.lower - x, x - problem.upper)))
        message = message or (
            f"{problem.names[worst]} = {x[worst]:.6g} outside "
            f"[{problem.lower[worst]:.6g}, {problem.upper[worst]:.6g}]"
            + ("" if claims_bounds else " (this method ignores the bounds)")
        )
    act_tol = max(tol.bounds, 1e-9)
    # Built field by field: dataclasses.replace costs ~5 us, a third of a fast solve.
    return StepSolution(
        x=x,
        status=status,
        objective=problem.objective(x),
        eq_residual=eq,
        bound_violation=viol,
        active_lower=x <= problem.lower + act_tol,
        active_upper=x >= problem.upper - act_tol,
        scale=solution.scale,
        solve_time=solution.solve_time,
        build_time=problem.build_time,
        solver=solution.solver,
        message=message,
        extras=solution.extras,
    )


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
