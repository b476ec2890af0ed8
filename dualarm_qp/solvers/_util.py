"""Small helpers shared by the solver modules (private)."""

from __future__ import annotations

from ..step.problem import StepProblem
from .base import Status, StepSolution, failed


def bound_label(problem: StepProblem, index: int, upper: bool) -> str:
    """Human-readable name of one bound, e.g. ``"q3 upper"``."""
    return f"{problem.names[index]} {'upper' if upper else 'lower'}"


def empty_box_failure(problem: StepProblem, solver: str, solve_time: float = 0.0
                      ) -> StepSolution | None:
    """INFEASIBLE solution naming the empty boxes (``lower > upper``), or None if there are none.

    The conflicts are the names of the variables whose box is empty; they are also
    stored in ``extras["conflicts"]``.
    """
    if not (problem.lower > problem.upper).any():
        return None
    names = problem.empty_bounds()
    return failed(problem, Status.INFEASIBLE, solver,
                  f"empty box (lower > upper) for {', '.join(names)}",
                  solve_time, conflicts=names)
