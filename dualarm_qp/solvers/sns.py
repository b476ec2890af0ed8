"""Saturation in the Null Space (SNS) with task scaling.

Flacco, De Luca and Khatib, "Prioritized multi-task motion control of redundant robots
under hard joint constraints", IROS 2012 / "Control of redundant robots under hard
joint constraints: saturation in the null space", IEEE TRO 31(3), 2015 (Algorithm 1).

For a working set of saturated variables (held at a bound) the free variables follow
the paper's weighted least-distance step restricted to them,

    x_F(s) = c_F + S_F^-1/2 (A_F S_F^-1/2)^+ (s b - A_sat x_sat - A_F c_F),

which is affine in the task scale ``s``: ``x(s) = s a + base``. Starting from the full
task and nothing saturated (but the pinched boxes, ``lower == upper``), SNS repeatedly
(1) stops if ``x(s)`` is inside the box, (2) otherwise computes the largest feasible
scale of the current working set and remembers the best one, (3) saturates the most
critical variable (the one that limits that scale) at the bound it hits. When the free
variables can no longer realise the task (rank of ``A_F`` below m) the best remembered
working set is used with its scale.

This is not the QP optimum in general; the bounds hold exactly and ``A x = s b``.
The secondary task is the centring term of Eq. 37, projected in the null space.

Like the original, the task scaling relies on ``s = 0`` being reachable, i.e. on
``x = 0`` (or the saturated variant of it) meeting the bounds: true when the state is
inside its limits. A step whose box excludes 0 may be reported INFEASIBLE although
it is feasible; :func:`~.policy.solve_step` then returns that failure unchanged.
"""

from __future__ import annotations

import time

import numpy as np
from numpy.typing import NDArray

from ..step.problem import StepProblem
from ._util import bound_label, empty_box_failure
from .base import DEFAULT_TOLERANCE, Status, StepSolution, Tolerance, failed, verify
from .registry import register

FloatArray = NDArray[np.float64]


class SNSSolver:
    """Saturation in the null space with task scaling (hard bounds, not a QP).

    Parameters
    ----------
    feasibility_tol : float
        Bound violation [rad/s or m/s] tolerated before a variable is saturated.
    tol : Tolerance
        Tolerances used by :func:`~.base.verify`.
    """

    name = "sns"

    def __init__(self, *, feasibility_tol: float = 1e-10,
                 tol: Tolerance = DEFAULT_TOLERANCE) -> None:
        self.feasibility_tol = float(feasibility_tol)
        self.tol = tol

    def solve(self, problem: StepProblem) -> StepSolution:
        """Run SNS; OPTIMAL when the full task is met, SCALED when it had to be scaled.

        The centring term has lower priority than the task: when the task cannot be met
        in full with it, SNS is run again without it (plain weighted SNS, ``c = 0``) and
        the run reaching the larger task scale is kept (``extras["centring"]``).
        """
        start = time.perf_counter()
        empty = empty_box_failure(problem, self.name)
        if empty is not None:
            return empty
        cap = float(problem.task_scale_max)
        run = self._run(problem, problem.center)
        centring = True
        if run[0] is None or run[1] < cap:
            plain = self._run(problem, np.zeros(problem.n))
            if plain[0] is not None and (run[0] is None or plain[1] > run[1]):
                run, centring = plain, False
        x, scale, saturated = run
        elapsed = time.perf_counter() - start
        if x is None:
            return failed(problem, Status.INFEASIBLE, self.name,
                          "no task scale in [0, task_scale_max] meets the bounds; "
                          f"saturated: {', '.join(saturated) or 'none'}",
                          elapsed, conflicts=saturated)
        # Nothing saturated while centring: SNS then returns the weighted least-distance
        # point itself, the minimiser of Eq. 37; otherwise it only claims feasibility.
        if scale < 1.0:
            status = Status.SCALED
        elif centring and not saturated:
            status = Status.OPTIMAL
        else:
            status = Status.FEASIBLE
        return verify(problem, StepSolution(
            x=np.clip(x, problem.lower, problem.upper), status=status, scale=scale,
            solver=self.name, solve_time=elapsed,
            extras={"saturated": saturated, "centring": centring}), self.tol)

    def _run(self, problem: StepProblem, center: FloatArray
             ) -> tuple[FloatArray | None, float, tuple[str, ...]]:
        """One SNS pass (Algorithm 1) toward ``center``: ``(x or None, scale, saturated)``."""
        lower, upper = problem.lower, problem.upper
        cap = float(problem.task_scale_max)
        tol = self.feasibility_tol
        # A pinched box (lower == upper, e.g. a fixed grasp) is saturated from the start.
        free = upper - lower > tol
        x_sat = np.where(free, 0.0, lower)
        best: tuple[float, FloatArray, FloatArray] | None = None
        x: FloatArray | None = None
        scale = cap
        for _ in range(problem.n + 1):
            split = _affine_in_scale(problem, center, free, x_sat)
            if split is None:
                break
            a, base = split
            x = cap * a + base
            if ((x >= lower - tol) & (x <= upper + tol)).all():
                break
            s_feasible, critical, at_upper = _scale_factor(a, base, lower, upper, free, cap, tol)
            if s_feasible >= 0.0 and (best is None or s_feasible > best[0]):
                best = (s_feasible, a, base)
            free[critical] = False
            x_sat[critical] = upper[critical] if at_upper else lower[critical]
            x = None
        if x is None and best is not None:
            scale, a, base = best
            x = scale * a + base
        saturated = tuple(bound_label(problem, int(i), bool(x_sat[i] >= upper[i]))
                          for i in np.flatnonzero(~free))
        if x is None or not ((x >= lower - tol) & (x <= upper + tol)).all():
            return None, -1.0, saturated
        return x, scale, saturated


def _affine_in_scale(problem: StepProblem, center: FloatArray, free: NDArray[np.bool_],
                     x_sat: FloatArray) -> tuple[FloatArray, FloatArray] | None:
    """Write the SNS step of this working set as ``x(s) = s a + base``.

    Returns ``(a, base)``, or None when the free variables cannot realise the task
    (``rank A_F < m``).
    """
    A, w, c = problem.A, problem.weights, center
    if int(free.sum()) < problem.m:
        return None
    inv_sqrt = 1.0 / np.sqrt(w[free])
    M = A[:, free] * inv_sqrt
    U, sv, Vt = np.linalg.svd(M, full_matrices=False)
    if sv.size == 0 or sv[-1] <= max(M.shape) * np.finfo(float).eps * sv[0]:
        return None
    M_pinv = (Vt.T / sv) @ U.T
    fixed = ~free
    a = np.zeros(problem.n)
    base = np.where(fixed, x_sat, 0.0)
    a[free] = inv_sqrt * (M_pinv @ problem.b)
    base[free] = c[free] + inv_sqrt * (M_pinv @ (-A[:, fixed] @ x_sat[fixed]
                                                 - A[:, free] @ c[free]))
    return a, base


def _scale_factor(a: FloatArray, base: FloatArray, lower: FloatArray, upper: FloatArray,
                  free: NDArray[np.bool_], cap: float, tol: float
                  ) -> tuple[float, int, bool]:
    """Find the task scale of a working set and its most critical variable.

    Returns the largest ``s`` in ``[0, cap]`` keeping the free variables in the box,
    the most critical variable, and whether it is to be saturated at its upper bound.

    The scale is -1 when no ``s`` works for this working set. The most critical
    variable is, in this order: a free variable the task does not move (``a_i = 0``)
    that lies outside its box; the one with the smallest upper scale limit below
    ``cap`` (Flacco et al.); the one most outside its box at ``s = cap``.
    """
    idx = np.flatnonzero(free)
    ai, bi, lo, up = a[idx], base[idx], lower[idx], upper[idx]
    moving = np.abs(ai) > 1e-14 * max(1.0, float(np.abs(ai).max()))
    stuck_excess = np.where(moving, 0.0, np.maximum(lo - bi, bi - up))
    j = int(np.argmax(stuck_excess))
    if stuck_excess[j] > tol:
        return -1.0, int(idx[j]), bool(bi[j] > up[j])
    safe = np.where(moving, ai, 1.0)
    s_lo = np.where(moving, np.where(ai > 0, lo - bi, up - bi) / safe, -np.inf)
    s_hi = np.where(moving, np.where(ai > 0, up - bi, lo - bi) / safe, np.inf)
    j = int(np.argmin(s_hi))
    if s_hi[j] < cap:
        critical, at_upper = int(idx[j]), bool(ai[j] > 0)
    else:
        x_cap = cap * ai + bi
        j = int(np.argmax(np.maximum(lo - x_cap, x_cap - up)))
        critical, at_upper = int(idx[j]), bool(x_cap[j] > up[j])
    s_min = max(0.0, float(s_lo.max(initial=-np.inf)))
    s_max = min(cap, float(s_hi.min(initial=np.inf)))
    if s_min > s_max or s_max < 0.0:
        return -1.0, critical, at_upper
    return s_max, critical, at_upper


register("sns", SNSSolver,
         description="Saturation in the Null Space (Flacco et al. 2012/2015), task scaling",
         hard_bounds=True)
