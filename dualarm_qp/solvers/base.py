"""The solver interface: a step problem goes in, a step solution comes out."""

from __future__ import annotations

import enum
from dataclasses import dataclass, field
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
        return self in _USABLE


#: The statuses whose ``x`` may be integrated (a set: a hash and an identity test, where
#: naming each member on the class costs 0.1 us in Python 3.11).
_USABLE = frozenset({Status.OPTIMAL, Status.FEASIBLE, Status.SCALED, Status.RELAXED,
                     Status.RECOVERING, Status.ESCAPING})


@dataclass(frozen=True)
class Tolerance:
    """Tolerances a solution must meet to be called a success.

    Parameters
    ----------
    equality : float
        Largest allowed ``|A x - b|`` component, relative to ``max(1, max |b|)`` of the
        right-hand side the answer was asked for (the scaled one for a scaled task)
        [m/s or rad/s].
    bounds : float
        Largest allowed violation of a box or of a (unit-norm) row [rad/s or m/s]; the
        one feasibility tolerance of every answer.
    """

    equality: float = 1e-7
    bounds: float = 1e-7


DEFAULT_TOLERANCE = Tolerance()


@dataclass(slots=True)
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
        ``max |A x - b|`` for the right-hand side the answer was asked for.
    bound_violation : float
        ``max(lower - x, x - upper, 0)``.
    active_lower, active_upper : ndarray of bool, shape (n,)
        Bounds active at ``x`` (within tolerance).
    row_violation : float
        Largest violation of a general row, ``max((G x - h)_i / |G_i|, 0)``.
    active_rows : tuple of str
        General rows active at ``x`` (within tolerance).
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
        The tolerances :func:`~.certify.certify` checked this solution against; None
        for a solver's raw claim, before certification.
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
    row_violation: float = 0.0
    active_rows: tuple[str, ...] = ()

    @property
    def success(self) -> bool:
        """Whether ``x`` may be integrated (see :attr:`Status.usable`)."""
        return self.status.usable


@runtime_checkable
class StepSolver(Protocol):
    """What every solver in the registry provides.

    A solver is built once (with its options) and called once per step. It may keep
    state between calls (a factorisation, a warm start), but must give a correct
    answer for any problem handed to it. It returns its *claim* (a status and ``x``);
    :func:`~dualarm_qp.solvers.get_solver` hands out every registered solver wrapped so
    that each answer is certified once (:func:`~.certify.certify`) before anyone reads
    it.
    """

    name: str

    def solve(self, problem: StepProblem) -> StepSolution:
        """Solve one step problem; return the claimed status and ``x``."""
        ...


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
