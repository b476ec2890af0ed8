"""Small helpers shared by the solver modules (private)."""

from __future__ import annotations

from ..step.problem import StepProblem
from .base import Status, StepSolution, failed


def bound_label(problem: StepProblem, index: int, upper: bool) -> str:
    """Human-readable name of one bound, e.g. ``"q3 upper"``."""
    return f"{problem.names[index]} {'upper' if upper else 'lower'}"


def empty_box_failure(problem: StepProblem, solver: str, solve_time: float = 0.0,
                      note: str = "", **extras: object) -> StepSolution | None:
    """INFEASIBLE solution naming the empty boxes (``lower > upper``), or None if there are none.

    The one answer to an empty box, for every solver and the policies
    (:func:`empty_box_answer`).
    """
    if not problem.has_empty_box():
        return None
    return empty_box_answer(problem, solver, solve_time, note, **extras)


def empty_box_answer(problem: StepProblem, solver: str, solve_time: float = 0.0,
                     note: str = "", **extras: object) -> StepSolution:
    """INFEASIBLE solution naming the empty boxes of a problem that has some.

    For a caller that found the empty box itself (the exact solver's kernel call). The
    conflicts are the names of the variables whose box is empty; they are also stored
    in ``extras["conflicts"]``. ``note`` is appended to the message.
    """
    names = problem.empty_bounds()
    return failed(problem, Status.INFEASIBLE, solver,
                  f"empty box (lower > upper) for {', '.join(names)}{note}",
                  solve_time, conflicts=names, **extras)
