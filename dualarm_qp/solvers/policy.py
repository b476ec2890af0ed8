"""What to do when a step is infeasible: scale the task, relax it, or stop.

:func:`solve_step` wraps any registered solver. A usable answer is returned as is. When
the solver gives none (INFEASIBLE, ERROR, or a VIOLATION it did not mean) the step is
checked for feasibility (:func:`~._affine.max_task_scale`). A feasible step is the
solver's fault, not the step's: it is solved again by the ``fallback`` solver when one
is given (see below), else the solver's own failure is returned. An infeasible step
gets:

``"scale"``
    the largest ``s`` in ``[0, task_scale_max]`` with ``{A x = s b, box}`` non-empty
    (closed form for a one-dimensional null space, an LP otherwise), then the solver on
    the task ``s b``; status SCALED with ``solution.scale = s``. If the solver fails on
    that (degenerate) problem, the ``fallback`` solves it when given; failing that, the
    feasible point found with ``s`` is returned. If not
    even ``s = 0`` is feasible, falls back to ``"relax"``. The whole right-hand side is
    scaled, so a closure-correction term in ``b`` is slowed with the task (at ``s = 0``
    the step holds still and corrects nothing; nothing moves, so no new drift
    arises either).
``"relax"``
    ``min ||A x - b||^2 + eps ||x - c||_S^2 / max(S)`` over the box (bounded least
    squares, BVLS): the bounds hold, the task is met in least squares; status RELAXED.
``"stop"``
    raise :class:`~dualarm_qp.errors.InfeasibleStepError` naming the conflicting bounds.

An empty box (``lower > upper``) cannot be relaxed: ``"scale"`` and ``"relax"`` return
INFEASIBLE with the empty boxes in ``extras["conflicts"]``; ``"stop"`` raises.

Fallback. With ``fallback`` given (e.g. the exact ``nullspace`` solver), a feasible
step that the solver failed is solved by the fallback, and the answer is the
fallback's (its status, ``x`` and extras, verified with ``tol``), with

* ``solution.solver``: still the primary solver's name;
* ``extras["fallback"] = {"from": <primary name>, "to": <fallback name>,
  "status": <the primary's failed status value>, "message": <its message>}``;
* ``solution.message``: ``"<primary> <status> (<its message>); solved by <fallback>"``;
* ``solution.solve_time``: both solves and the feasibility check.

No new status is used: the fallback is recorded only in ``extras["fallback"]``. The
default is no fallback, so that a benchmark measures each solver's own success.
"""

from __future__ import annotations

import dataclasses
import time
from typing import Any, Literal

import numpy as np
from scipy.optimize import lsq_linear

from ..errors import InfeasibleStepError, InvalidInputError
from ..step.problem import StepProblem
from ._affine import TaskScale, max_task_scale
from ._util import bound_label
from .base import DEFAULT_TOLERANCE, Status, StepSolution, StepSolver, Tolerance, failed, verify

Policy = Literal["scale", "relax", "stop"]
POLICIES: tuple[str, ...] = ("scale", "relax", "stop")

#: Weight of the centring term in the relaxed problem (relative to the task residual,
#: with S normalised by its largest entry).
RELAX_EPS = 1e-8


def solve_step(solver: StepSolver, problem: StepProblem, policy: Policy = "scale", *,
               tol: Tolerance = DEFAULT_TOLERANCE, relax_eps: float = RELAX_EPS,
               fallback: StepSolver | None = None) -> StepSolution:
    """Solve one step with ``solver`` and apply ``policy`` if the step is infeasible.

    Parameters
    ----------
    solver : StepSolver
        Any registered solver.
    problem : StepProblem
        The step.
    policy : {"scale", "relax", "stop"}
        What to do with an infeasible step (see the module docstring).
    tol : Tolerance
        Tolerances used to verify the policy's answer.
    relax_eps : float
        Weight of the centring term in ``"relax"`` (dimensionless).
    fallback : StepSolver or None
        Solver for the steps that are feasible but that ``solver`` failed (and for a
        failed inner solve of ``"scale"``); None (the default) keeps the failure.

    Returns
    -------
    StepSolution
        Never contains NaN. ``extras["policy"]`` records the policy applied, if any;
        ``extras["fallback"]`` records a fallback (see the module docstring).

    Raises
    ------
    InfeasibleStepError
        Policy ``"stop"`` on an infeasible step; ``conflicts`` names the bounds.
    InvalidInputError
        Unknown policy.
    """
    if policy not in POLICIES:
        raise InvalidInputError(f"unknown policy '{policy}' (valid: {', '.join(POLICIES)})")
    solution = solver.solve(problem)
    if solution.status.usable:
        return solution
    # Policy time is counted from the first solve, which it includes.
    start = time.perf_counter() - solution.solve_time
    # The exact solver may have computed the task scale of this very problem already.
    known = solution.extras.get("task_scale")
    reach = known if isinstance(known, TaskScale) else max_task_scale(problem, cap=1.0)
    if reach.scale is not None and reach.scale >= 1.0 - 1e-12:
        # The step is feasible: the failure is the solver's own.
        if fallback is None:
            return solution
        return _fell_back(solution, fallback, problem, solver.name, tol, start)
    if policy == "stop":
        conflicts = reach.blocking or _relaxed_conflicts(problem, relax_eps)
        raise InfeasibleStepError(
            f"step infeasible for solver '{solver.name}' "
            f"(largest feasible task scale: {_fmt(reach.scale)})", conflicts=conflicts)
    if policy == "scale" and reach.scale is not None:
        return _scaled(solver, problem, reach, tol, start, fallback)
    return _relaxed(solver.name, problem, reach.blocking, relax_eps, tol, start)


def _fell_back(failure: StepSolution, fallback: StepSolver, problem: StepProblem,
               name: str, tol: Tolerance, start: float) -> StepSolution:
    """Solve a feasible step that the solver ``name`` failed with ``fallback``."""
    answer = fallback.solve(problem)
    record = _fallback_record(failure, name, fallback.name)
    message = f"{name} {failure.status.value} ({failure.message}); solved by {fallback.name}"
    if not answer.status.usable:
        message = (f"{name} {failure.status.value} ({failure.message}); the fallback "
                   f"{fallback.name} failed too: {answer.message}")
    elif answer.message:
        message += f": {answer.message}"
    return verify(problem, dataclasses.replace(
        answer, solver=name, message=message, solve_time=time.perf_counter() - start,
        extras={**answer.extras, "fallback": record}), tol)


def _fallback_record(failure: StepSolution, name: str, fallback: str) -> dict[str, str]:
    """``extras["fallback"]``: who failed, how, and who solved the step instead."""
    return {"from": name, "to": fallback, "status": failure.status.value,
            "message": failure.message}


def _scaled(solver: StepSolver, problem: StepProblem, reach: TaskScale, tol: Tolerance,
            start: float, fallback: StepSolver | None = None) -> StepSolution:
    """Solve the task scaled by the largest feasible ``s`` (capped by task_scale_max)."""
    if reach.scale is not None and reach.scale > problem.task_scale_max:
        reach = max_task_scale(problem, cap=problem.task_scale_max)
    s = float(reach.scale or 0.0)
    # The LP's point is feasible for the scaled task: a warm start (an exact solver's
    # active set starts there instead of solving the LP again).
    scaled = dataclasses.replace(problem, b=s * problem.b,
                                 x_prev=reach.x if reach.x is not None else problem.x_prev)
    inner = solver.solve(scaled)
    extras: dict[str, Any] = {"policy": "scale", "conflicts": reach.blocking,
                              "inner_status": inner.status}
    if not inner.status.usable and fallback is not None:
        second = fallback.solve(scaled)
        if second.status.usable:
            extras["fallback"] = _fallback_record(inner, solver.name, fallback.name)
            inner = second
    x = inner.x
    if inner.status.usable:
        s *= inner.scale  # 1 for every registered solver (they solve the task given)
    elif reach.x is not None:
        x = reach.x  # the feasible set at the largest s is (nearly) a single point
        extras["point"] = "feasibility"
    message = (f"task scaled to {s:.6g} of b; blocking bounds: "
               f"{', '.join(reach.blocking) or 'none'}")
    if "fallback" in extras:
        message += f"; solved by {extras['fallback']['to']} after {solver.name} failed"
    # ``start`` is the start of the first solve: the wall time since covers every solve.
    return verify(problem, StepSolution(
        x=x, status=Status.SCALED, scale=s, solver=solver.name, message=message,
        solve_time=time.perf_counter() - start, extras=extras), tol)


def _relaxed(name: str, problem: StepProblem, blocking: tuple[str, ...], relax_eps: float,
             tol: Tolerance, start: float) -> StepSolution:
    """Bounded least squares: the box holds, ``A x = b`` holds as well as it can."""
    if (problem.lower > problem.upper).any():
        names = problem.empty_bounds()
        return failed(problem, Status.INFEASIBLE, name,
                      f"empty box (lower > upper) for {', '.join(names)}: cannot relax",
                      time.perf_counter() - start, policy="relax", conflicts=names)
    x = _bounded_least_squares(problem, relax_eps)
    if x is None:
        return failed(problem, Status.ERROR, name, "bounded least squares failed",
                      time.perf_counter() - start, policy="relax", conflicts=blocking)
    residual = float(np.abs(problem.A @ x - problem.b).max())
    return verify(problem, StepSolution(
        x=x, status=Status.RELAXED, solver=name,
        message=f"task relaxed: |A x - b| = {residual:.3g}",
        solve_time=time.perf_counter() - start,
        extras={"policy": "relax", "conflicts": blocking or _active(problem, x)}), tol)


def _bounded_least_squares(problem: StepProblem, relax_eps: float) -> np.ndarray | None:
    """``argmin ||A x - b||^2 + eps ||x - c||_S^2 / max(S)`` over the (non-empty) box."""
    lower, upper = problem.lower, problem.upper
    pinned = upper - lower <= 0.0  # BVLS needs lower < upper: substitute pinned ones
    free = ~pinned
    x = np.where(pinned, lower, 0.0)
    if free.any():
        reg = np.sqrt(relax_eps * problem.weights[free] / problem.weights.max())
        M = np.vstack([problem.A[:, free], np.diag(reg)])
        rhs = np.concatenate([problem.b - problem.A[:, pinned] @ x[pinned],
                              reg * problem.center[free]])
        try:
            res = lsq_linear(M, rhs, bounds=(lower[free], upper[free]), method="bvls",
                             tol=1e-12, max_iter=100 * problem.n)
        except (ValueError, np.linalg.LinAlgError):
            return None
        x[free] = np.clip(res.x, lower[free], upper[free])
    return x if np.isfinite(x).all() else None


def _active(problem: StepProblem, x: np.ndarray) -> tuple[str, ...]:
    """Bounds active at ``x`` (within 1e-9), as labels."""
    lo = np.flatnonzero(x <= problem.lower + 1e-9)
    up = np.flatnonzero(x >= problem.upper - 1e-9)
    return (tuple(bound_label(problem, int(i), False) for i in lo)
            + tuple(bound_label(problem, int(i), True) for i in up))


def _relaxed_conflicts(problem: StepProblem, relax_eps: float) -> tuple[str, ...]:
    """Name the bounds in conflict when no LP certificate names them.

    These are the empty boxes if any, else the bounds active at the relaxed solution.
    """
    if (problem.lower > problem.upper).any():
        return problem.empty_bounds()
    x = _bounded_least_squares(problem, relax_eps)
    return _active(problem, x) if x is not None else problem.names


def _fmt(scale: float | None) -> str:
    return "none, even s = 0 is infeasible" if scale is None else f"{scale:.6g}"
