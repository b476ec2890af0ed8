"""Saturation in the Null Space (SNS) for the full task, with the centring term.

Flacco, De Luca and Khatib, "Prioritized multi-task motion control of redundant robots
under hard joint constraints", IROS 2012 / "Control of redundant robots under hard
joint constraints: saturation in the null space", IEEE TRO 31(3), 2015 (Algorithm 1).

The task is ``A x = b`` (priority 1) and the secondary task is the centring term of
Eq. 37: the velocity ``c`` (the range centres), projected in the null space of the task
and of the saturated variables with the metric ``S``. :meth:`SNSSolver.solve` solves the
*full* task (scale 1) in two phases.

1. **SNS** (Algorithm 1). For a working set of saturated variables (held at a bound;
   the pinched boxes ``lower == upper`` from the start) the free variables follow

       x_F(s) = c_F + S_F^-1/2 (A_F S_F^-1/2)^+ (s b - A_sat x_sat - A_F c_F),

   affine in the task scale ``s``: ``x(s) = s a + base``. While ``x(1)`` leaves the box,
   the most critical variable (the one that limits the task scale of the working set,
   Flacco et al.) is saturated at the bound it hits. The loop ends when ``x(1)`` is in
   the box (the answer) or when the free variables can no longer realise the task
   (``rank A_F < m``). The largest scale of the working sets visited, what the original
   SNS would return as its task scale, is kept in ``extras["sns_scale"]``.
2. **Completion**, only when phase 1 ends without the full task. The greedy saturation
   order is not always right. Measured on 300 random feasible steps, phase 1 misses
   the full task on 43% of the 6 x 7 ones and 52% of the 6 x 8 ones; with its own task
   scaling, the original SNS stopped short of the largest feasible scale on 30% of
   random infeasible 6 x 7 steps (down to 0.22 of it).
   The largest feasible scale ``s*`` is computed exactly (:func:`~._affine.max_task_scale`:
   closed form for a one-dimensional null space, an LP otherwise). If ``s* < 1`` the
   step is INFEASIBLE, with ``s*`` in ``extras["max_scale"]`` and its blocking bounds in
   ``extras["conflicts"]``. Otherwise SNS saturation is applied to the secondary task
   from the feasible point ``x1`` that comes with ``s*``: the centring velocity
   ``c - x`` is projected in the null space of ``A`` and of the saturated variables,
   scaled by the largest factor in ``[0, 1]`` the box allows, the variable limiting
   that factor is saturated, and the rest of the centring velocity is projected again.
   ``A x = b`` and the bounds hold along the way.

Task scaling is the policy's job: SNS never scales the task by itself. Under
:func:`~.policy.solve_step` with policy ``"scale"`` the task is scaled to ``s*`` (capped
by ``task_scale_max``) and SNS is called on ``s* b``, whose full task is feasible: the
scale reached is exactly ``s*``, as for the exact solvers. Under ``"relax"`` and
``"stop"`` SNS behaves like every other solver. ``task_scale_max`` is not read here.
A box need not contain ``x = 0`` (the original SNS needs it for its task scaling).

How the answer differs from the minimiser of Eq. 37 (the QP optimum)
--------------------------------------------------------------------
* Both phases saturate and never release: a variable held at a bound stays there even
  when its multiplier has the wrong sign (an active-set QP method would free it). The
  answer is the minimiser of Eq. 37 with the saturated variables held at their bounds:
  ``A x = b`` and the bounds hold, Eq. 37 is at least the optimum. Status FEASIBLE,
  the held bounds in ``extras["saturated"]`` and ``message``.
* The status is OPTIMAL exactly when the held bounds' multipliers have the right sign
  (KKT; pinched boxes are equalities and take any sign): the answer is then the unique
  minimiser. With nothing held that is the weighted least-distance step of the paper.
* One null direction (the paper's 6 x 7 step): every answer is the QP optimum. The
  feasible set is a segment; phase 1 holds one variable at the end of the segment
  nearest the unconstrained minimiser, and phase 2 walks along the segment towards it.
* Several null directions (6 x 8 and larger): measured on 300 random feasible 6 x 8
  steps, 81% of the answers are the optimum; the others are 10% above it in Eq. 37
  (median; from 2e-5 to 184% above). The phase-2 answer depends on its start ``x1``,
  an LP vertex.
* Under the ``"scale"`` policy the feasible set at ``s*`` is generically a single point,
  which every solver returns.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..step.problem import StepProblem
from ._affine import factor
from ._scale import FEASIBLE_SCALE_TOL, max_task_scale
from ._util import bound_label, empty_box_failure
from .base import DEFAULT_TOLERANCE, Status, StepSolution, Tolerance, failed
from .registry import check_number, check_tolerance, register

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


class SNSSolver:
    """Saturation in the null space for the full task (hard bounds, not a QP).

    Parameters
    ----------
    feasibility_tol : float
        Bound violation [rad/s or m/s] tolerated before a variable is saturated; boxes
        narrower than this are pinched (held at ``lower``).
    tol : Tolerance
        Tolerances of the certificate (:func:`~.certify.certify`).
    """

    name = "sns"

    def __init__(self, *, feasibility_tol: float = 1e-10,
                 tol: Tolerance = DEFAULT_TOLERANCE) -> None:
        check_number(self.name, "feasibility_tol", feasibility_tol, minimum=0.0, strict=True)
        check_tolerance(self.name, tol)
        self.feasibility_tol = float(feasibility_tol)
        self.tol = tol

    def solve(self, problem: StepProblem) -> StepSolution:
        """Solve the full task ``A x = b`` by SNS with the centring term.

        Parameters
        ----------
        problem : StepProblem
            The step (boxes only; scaling is the policy's job).

        Returns
        -------
        StepSolution
            The claim OPTIMAL (the certificate makes it FEASIBLE when the saturated
            set is not the optimal one), INFEASIBLE (``x = 0``) when the full task
            is infeasible; then ``extras["max_scale"]`` is the largest feasible task
            scale (None if not even ``s = 0`` is) and ``extras["conflicts"]`` the
            bounds blocking it. ``scale`` is always 1. ``extras["saturated"]`` names
            the bounds SNS held (pinched boxes excluded), ``extras["sns_scale"]`` is the
            task scale the original SNS reached (1 when phase 1 met the task; -1 when
            no working set had a feasible scale) and ``extras["completed"]`` whether
            phase 2 was needed.
        """
        start = time.perf_counter()
        empty = empty_box_failure(problem, self.name)
        if empty is not None:
            return empty
        tol = self.feasibility_tol
        pinched = problem.upper - problem.lower <= tol
        end, sns_scale = _saturate(problem, pinched, tol)
        extras: dict[str, Any] = {"sns_scale": sns_scale, "completed": end is None}
        if end is None:
            reach = max_task_scale(problem, cap=1.0)
            extras["max_scale"] = reach.scale
            if reach.scale is None or reach.x is None or reach.scale < 1.0 - FEASIBLE_SCALE_TOL:
                scale = ("none (not even s = 0)" if reach.scale is None
                         else f"{reach.scale:.6g}")
                return failed(problem, Status.INFEASIBLE, self.name,
                              f"full task infeasible; largest feasible task scale: {scale}; "
                              f"blocking: {', '.join(reach.blocking) or 'none'}",
                              time.perf_counter() - start, conflicts=reach.blocking,
                              **extras)
            end = _centre_in_null_space(problem, reach.x, pinched)
        x, free, lam = end
        x = np.clip(x, problem.lower, problem.upper)
        held = np.flatnonzero(~free & ~pinched)
        held_upper = [bool(x[i] >= problem.upper[i]) for i in held]
        extras["saturated"] = tuple(bound_label(problem, int(i), up)
                                    for i, up in zip(held, held_upper, strict=True))
        # The claim: the minimiser of Eq. 37 with the saturated set held. Whether it is
        # the minimiser of the step is the certificate's decision (FEASIBLE otherwise).
        del lam
        message = ("SNS point; held: " + ", ".join(extras["saturated"])
                   if extras["saturated"] else "")
        return StepSolution(x=x, status=Status.OPTIMAL, solver=self.name, message=message,
                            solve_time=time.perf_counter() - start, extras=extras)


#: What a phase ends with: ``x`` (``A x = b``, in the box), the free variables, and the
#: task multipliers ``lam`` of that working set (``S (x - c) = A^T lam`` on the free
#: variables; ``x`` is the minimiser of Eq. 37 with the others held where they are).
End = tuple[FloatArray, BoolArray, FloatArray]


def _saturate(problem: StepProblem, pinched: BoolArray, tol: float
              ) -> tuple[End | None, float]:
    """Phase 1, Algorithm 1 of Flacco et al. for the full task, with the centring term.

    Returns
    -------
    end : (x, free, lam) or None
        The SNS point meeting ``A x = b`` in the box, the variables left free and the
        task multipliers; None when the saturation sequence ends without the task.
    sns_scale : float
        1.0 when the point was found, else the largest task scale of the working sets
        visited (-1 when none had one): what the original SNS would have returned.
    """
    lower, upper = problem.lower, problem.upper
    free = ~pinched
    x_sat = np.where(free, 0.0, lower)
    best = -1.0
    for _ in range(problem.n + 1):
        split = _affine_in_scale(problem, free, x_sat)
        if split is None:
            break
        a, base, lam_a, lam_base = split
        x = a + base
        if ((x >= lower - tol) & (x <= upper + tol)).all():
            return (x, free, lam_a + lam_base), 1.0
        s_feasible, critical, at_upper = _scale_factor(a, base, lower, upper, free, 1.0, tol)
        best = max(best, s_feasible)
        free[critical] = False
        x_sat[critical] = upper[critical] if at_upper else lower[critical]
    return None, best


def _affine_in_scale(problem: StepProblem, free: BoolArray, x_sat: FloatArray
                     ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray] | None:
    """Write the SNS step of this working set as ``x(s) = s a + base``.

    Returns ``(a, base, lam_a, lam_base)`` with the task multipliers
    ``lam(s) = s lam_a + lam_base``, or None when the free variables cannot realise the
    task (``rank A_F < m``).
    """
    A, w, c, m = problem.A, problem.weights, problem.center, problem.m
    fixed = ~free
    a = np.zeros(problem.n)
    base = np.where(fixed, x_sat, 0.0)
    if m == 0:
        base[free] = c[free]
        return a, base, np.zeros(0), np.zeros(0)
    if int(free.sum()) < m:
        return None
    inv_sqrt = 1.0 / np.sqrt(w[free])
    f = factor(A[:, free] * inv_sqrt)
    if f.rank < m:  # the free variables cannot realise the task
        return None
    U, sv, Vt = f.U, f.sigma, f.V.T
    # x_F = c_F + S_F^-1/2 M^+ r and M^+ r = M^T lam with lam = U sv^-2 U^T r.
    r_b = U.T @ problem.b
    r_c = U.T @ (-A[:, fixed] @ x_sat[fixed] - A[:, free] @ c[free])
    a[free] = inv_sqrt * (Vt.T @ (r_b / sv))
    base[free] = c[free] + inv_sqrt * (Vt.T @ (r_c / sv))
    return a, base, U @ (r_b / sv**2), U @ (r_c / sv**2)


def _scale_factor(a: FloatArray, base: FloatArray, lower: FloatArray, upper: FloatArray,
                  free: BoolArray, cap: float, tol: float) -> tuple[float, int, bool]:
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


def _centre_in_null_space(problem: StepProblem, x1: FloatArray, pinched: BoolArray) -> End:
    """Phase 2: SNS saturation of the centring task from a feasible point ``x1``.

    Each round projects the centring velocity ``c - x`` in the null space of ``A`` and
    of the saturated variables (metric ``S``), scales it by the largest factor in
    ``[0, 1]`` that keeps the box, and saturates the variable that limits the factor.
    Ends when the factor is 1 or nothing is left free, at the minimiser of Eq. 37 with
    the saturated variables held (``A x`` is left unchanged).
    """
    lower, upper, c = problem.lower, problem.upper, problem.center
    x = np.clip(x1, lower, upper)
    free = ~pinched
    lam = np.zeros(problem.m)
    for _ in range(problem.n + 1):
        d, lam = _null_space_step(problem, free, c - x)
        factor, block, block_upper = 1.0, -1, False
        for i in np.flatnonzero(free & (d != 0.0)):
            di = float(d[i])
            room = (upper[i] if di > 0.0 else lower[i]) - x[i]
            ratio = max(room / di, 0.0)
            if ratio < factor:
                factor, block, block_upper = ratio, int(i), di > 0.0
        x = x + factor * d
        if block < 0:
            break
        free[block] = False
        x[block] = upper[block] if block_upper else lower[block]
    return x, free, lam


def _null_space_step(problem: StepProblem, free: BoolArray, v: FloatArray
                     ) -> tuple[FloatArray, FloatArray]:
    """``d = argmin ||d - v||_S`` over ``A d = 0`` with ``d = 0`` off ``free``.

    Also returns the task multipliers at ``x + d`` (``x = c - v``): ``lam`` with
    ``S_F (x + d - c)_F = A_F^T lam`` (least squares when ``A_F`` is rank-deficient).
    """
    d = np.zeros(problem.n)
    lam = np.zeros(problem.m)
    if not free.any():
        return d, lam
    sqrt_w = np.sqrt(problem.weights[free])
    y = sqrt_w * v[free]
    if problem.m:
        f = factor(problem.A[:, free] / sqrt_w)
        U, sv, Vt = f.U, f.sigma, f.V.T
        proj = Vt @ y
        y = y - Vt.T @ proj
        # S_F^1/2 (x + d - c)_F = -Vt^T proj = M^T lam with M = U sv Vt.
        lam = -U @ (proj / sv)
    d[free] = y / sqrt_w
    return d, lam


register("sns", SNSSolver,
         description="Saturation in the Null Space (Flacco et al. 2012/2015), full task; "
                     "task scaling by the policy; boxes only",
         hard_bounds=True, takes_rows=False, dense_cost=False)
