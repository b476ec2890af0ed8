"""What to do when a step is infeasible: scale the task, relax it, or stop.

:func:`solve_step` wraps any solver. Every answer in it comes from a certified solve
(:class:`~.registry.CertifiedSolver`: each claim is checked once, by
:func:`~.certify.certify`, against the problem it was asked), so nothing here checks an
answer again. A usable answer is returned as is. When the solver gives none
(INFEASIBLE, ERROR, or a VIOLATION it did not mean) the step's largest feasible task
scale is computed exactly (:func:`~._scale.max_task_scale`: every box and row). A step
feasible at full scale is the solver's fault, not the step's: it is solved again by the
``fallback`` solver when one is given, else the solver's own failure is returned. An
infeasible step gets:

``"scale"``
    the largest ``s`` in ``[0, 1]`` with ``{A x = s b, boxes, rows}``
    non-empty, then the solver on the task ``s b`` (its answer certified against that
    scaled problem); status SCALED with ``solution.scale = s``. If the solver fails on
    that (degenerate) problem, the ``fallback`` solves it when given; failing that, the
    feasible point found with ``s`` is returned, certified as it is. If not even
    ``s = 0`` is feasible, falls back to ``"relax"``. The whole right-hand side is
    scaled, so a closure-correction term in ``b`` is slowed with the task (at ``s = 0``
    the step holds still and corrects nothing; nothing moves, so no new drift arises
    either).
``"relax"``
    ``min ||A x - b||^2 + eps ||x - c||_W^2 / max(W)`` subject to every box and row (a
    strictly convex QP, solved by the dual active-set method of :mod:`._dense_qp`): the
    limits hold, the task is met in least squares; status RELAXED.
``"stop"``
    raise :class:`~dualarm_qp.errors.InfeasibleStepError` naming the conflicting limits.

An empty box (``lower > upper``) cannot be relaxed: ``"scale"`` and ``"relax"`` return
INFEASIBLE with the empty boxes in ``extras["conflicts"]``; ``"stop"`` raises.

Fallback. With ``fallback`` given (e.g. the exact ``nullspace`` solver), a feasible
step that the solver failed is solved by the fallback, and the answer is the
fallback's (its status, ``x`` and extras), with

* ``solution.solver``: still the primary solver's name;
* ``extras["fallback"] = {"from": <primary name>, "to": <fallback name>,
  "status": <the primary's failed status value>, "message": <its message>}``;
* ``solution.message``: ``"<primary> <status> (<its message>); solved by <fallback>"``;
* ``solution.solve_time``: both solves and the feasibility check.

The default is no fallback, so that a benchmark measures each solver's own success.
"""

from __future__ import annotations

import dataclasses
import time
from typing import Any, Literal

import numpy as np

from ..errors import InfeasibleStepError, InvalidInputError
from ..step.problem import StepProblem
from ._dense_qp import solve_dense_qp
from ._scale import TaskScale, max_task_scale
from ._util import empty_box_failure
from .base import DEFAULT_TOLERANCE, Status, StepSolution, StepSolver, Tolerance, failed
from .certify import certify
from .registry import certified

Policy = Literal["scale", "relax", "stop"]
POLICIES: tuple[str, ...] = ("scale", "relax", "stop")

#: Weight of the centring term in the relaxed problem (relative to the task residual,
#: with W normalised by its largest entry).
RELAX_EPS = 1e-8


def solve_step(solver: StepSolver, problem: StepProblem, policy: Policy = "scale", *,
               tol: Tolerance = DEFAULT_TOLERANCE, relax_eps: float = RELAX_EPS,
               fallback: StepSolver | None = None) -> StepSolution:
    """Solve one step with ``solver`` and apply ``policy`` if the step is infeasible.

    Parameters
    ----------
    solver : StepSolver
        Any solver (one not from the registry is certified with ``tol``).
    problem : StepProblem
        The step.
    policy : {"scale", "relax", "stop"}
        What to do with an infeasible step (see the module docstring).
    tol : Tolerance
        Tolerances of the certificate for a solver not from the registry and for the
        policy's own answers.
    relax_eps : float
        Weight of the centring term in ``"relax"`` (dimensionless).
    fallback : StepSolver or None
        Solver for the steps that are feasible but that ``solver`` failed (and for a
        failed inner solve of ``"scale"``); None (the default) keeps the failure.

    Returns
    -------
    StepSolution
        Certified, never NaN. ``extras["policy"]`` records the policy applied, if any;
        ``extras["fallback"]`` records a fallback (see the module docstring).

    Raises
    ------
    InfeasibleStepError
        Policy ``"stop"`` on an infeasible step; ``conflicts`` names the limits.
    InvalidInputError
        Unknown policy.
    """
    if policy not in POLICIES:
        raise InvalidInputError(f"unknown policy '{policy}' (valid: {', '.join(POLICIES)})")
    solver = certified(solver, tol)
    solution = solver.solve(problem)
    if solution.status.usable:
        return solution
    return _after_failure(solver, problem, solution, policy, tol, relax_eps, fallback)


def _after_failure(solver: Any, problem: StepProblem, solution: StepSolution,
                   policy: Policy, tol: Tolerance, relax_eps: float,
                   fallback: StepSolver | None) -> StepSolution:
    """Apply the policy and the fallback to a step the solver gave no usable answer to."""
    # Policy time is counted from the first solve, which it includes.
    start = time.perf_counter() - solution.solve_time
    known = solution.extras.get("task_scale")
    reach = known if isinstance(known, TaskScale) else max_task_scale(problem, cap=1.0)
    if reach.full:
        # The step is feasible: the failure is the solver's own.
        if fallback is None:
            return solution
        return _fell_back(solution, certified(fallback, tol), problem, solver.name, start)
    if policy == "stop":
        conflicts = reach.blocking or problem.empty_bounds() or _relaxed_conflicts(
            problem, relax_eps)
        raise InfeasibleStepError(
            f"step infeasible for solver '{solver.name}' "
            f"(largest feasible task scale: {_fmt(reach.scale)})", conflicts=conflicts)
    if policy == "scale" and reach.scale is not None:
        return _scaled(solver, problem, reach, tol, start,
                       None if fallback is None else certified(fallback, tol))
    return _relaxed(solver.name, problem, reach.blocking, relax_eps, tol, start)


def _fell_back(failure: StepSolution, fallback: StepSolver, problem: StepProblem,
               name: str, start: float) -> StepSolution:
    """Solve a feasible step that the solver ``name`` failed with ``fallback``."""
    answer = fallback.solve(problem)
    record = _fallback_record(failure, name, fallback.name)
    message = f"{name} {failure.status.value} ({failure.message}); solved by {fallback.name}"
    if not answer.status.usable:
        message = (f"{name} {failure.status.value} ({failure.message}); the fallback "
                   f"{fallback.name} failed too: {answer.message}")
    elif answer.message:
        message += f": {answer.message}"
    return dataclasses.replace(answer, solver=name, message=message,
                               solve_time=time.perf_counter() - start,
                               extras={**answer.extras, "fallback": record})


def _fallback_record(failure: StepSolution, name: str, fallback: str) -> dict[str, str]:
    """``extras["fallback"]``: who failed, how, and who solved the step instead."""
    return {"from": name, "to": fallback, "status": failure.status.value,
            "message": failure.message}


def _scaled(solver: StepSolver, problem: StepProblem, reach: TaskScale, tol: Tolerance,
            start: float, fallback: StepSolver | None = None) -> StepSolution:
    """Solve the task scaled by the largest feasible ``s``."""
    s = float(reach.scale or 0.0)
    # The LP's point is feasible for the scaled task: a warm start (an exact solver's
    # active set may start there).
    scaled = problem.scaled(s, x_prev=reach.x)
    inner = solver.solve(scaled)
    extras: dict[str, Any] = {"policy": "scale", "conflicts": reach.blocking,
                              "inner_status": inner.status,
                              "rank_limited": reach.rank_limited}
    if not inner.status.usable and fallback is not None:
        second = fallback.solve(scaled)
        if second.status.usable:
            extras["fallback"] = _fallback_record(inner, solver.name, fallback.name)
            inner = second
    if not inner.status.usable and reach.x is not None:
        # The feasible set at the largest s is (nearly) a single point: the LP's.
        inner = certify(scaled, StepSolution(x=reach.x, status=Status.FEASIBLE,
                                             solver=solver.name), tol)
        extras["point"] = "feasibility"
    message = (f"task scaled to {s:.6g} of b; blocking limits: "
               f"{', '.join(reach.blocking) or 'none'}"
               + ("; the step lost rank (an arm at a singularity)" if reach.rank_limited
                  else ""))
    if "fallback" in extras:
        message += f"; solved by {extras['fallback']['to']} after {solver.name} failed"
    status = Status.SCALED if inner.status.usable else inner.status
    # ``start`` is the start of the first solve: the wall time since covers every solve.
    return dataclasses.replace(inner, status=status, scale=s * inner.scale,
                               solver=solver.name, message=message if status.usable
                               else inner.message, solve_time=time.perf_counter() - start,
                               extras={**inner.extras, **extras})


def _relaxed(name: str, problem: StepProblem, blocking: tuple[str, ...], relax_eps: float,
             tol: Tolerance, start: float) -> StepSolution:
    """Least squares within every limit: the limits hold, ``A x = b`` as well as it can."""
    empty = empty_box_failure(problem, name, time.perf_counter() - start, ": cannot relax",
                              policy="relax")
    if empty is not None:
        return empty
    x = relaxed_point(problem, relax_eps)
    if x is None:
        return failed(problem, Status.ERROR, name,
                      "the limits admit no common point: cannot relax",
                      time.perf_counter() - start, policy="relax", conflicts=blocking)
    residual = float(np.abs(problem.A @ x - problem.b).max(initial=0.0))
    claim = StepSolution(x=x, status=Status.RELAXED, solver=name,
                         message=f"task relaxed: |A x - b| = {residual:.3g}",
                         extras={"policy": "relax",
                                 "conflicts": blocking or _active(problem, x)})
    out = certify(problem, claim, tol)
    return dataclasses.replace(out, solve_time=time.perf_counter() - start)


def relaxed_point(problem: StepProblem, relax_eps: float = RELAX_EPS) -> np.ndarray | None:
    """``argmin ||A x - b||^2 + eps ||x - c||_W^2 / max(W)`` over every box and row.

    None when the limits have no common point.
    """
    # The objective is |M x - r|^2 with M = [A; sqrt(eps / max W) R_W]: its QR gives the
    # triangular factor of the Hessian without squaring the condition number.
    root = problem.cost_root()
    top = float(np.abs(problem.weight_matrix()).max(initial=1.0)) or 1.0
    k = np.sqrt(relax_eps / top)
    M = np.vstack([problem.A, k * root])
    r = np.concatenate([problem.b, k * (root @ problem.center)])
    Q, R = np.linalg.qr(M)
    if not np.all(np.abs(np.diag(R)) > 0.0):
        return None
    t_free = np.linalg.solve(R, Q.T @ r)
    ineq = problem.inequalities()
    out = solve_dense_qp(R, t_free, ineq.C, ineq.e)
    if out.status != "optimal" or not np.isfinite(out.t).all():
        return None
    return np.clip(out.t, problem.lower, problem.upper)


def _active(problem: StepProblem, x: np.ndarray) -> tuple[str, ...]:
    """Limits active at ``x`` (within 1e-9), as labels."""
    ineq = problem.inequalities()
    on = ineq.C @ x - ineq.e >= -1e-9
    return ineq.labels(np.flatnonzero(on))


def _relaxed_conflicts(problem: StepProblem, relax_eps: float) -> tuple[str, ...]:
    """Name the limits in conflict when no LP certificate names them.

    These are the limits active at the relaxed solution.
    """
    x = relaxed_point(problem, relax_eps)
    return _active(problem, x) if x is not None else problem.names


def _fmt(scale: float | None) -> str:
    return "none, even s = 0 is infeasible" if scale is None else f"{scale:.6g}"
