"""The largest feasible task scale of a step: an exact small linear program (private).

For a right-hand side that moves along a line, ``A x = base + s direction``, find the
largest ``s`` in ``[0, cap]`` for which some ``x`` meets every box and row of the
step. The policy asks it with ``base = 0`` and ``direction = b`` (the task scale,
:func:`max_task_scale`).

Every solution of the equality is ``x = x_b + s x_d + N t`` (the exact solver's basis of
``A``, :func:`~._affine.null_basis`), so the problem is an LP in ``(t, s)``, a handful of
variables, with one row per finite bound and general row:

    maximise s   subject to   M t + a s <= g,   s_lo <= s <= s_hi.

It is solved through its dual, ``min g^T y + s_hi y_hi - s_lo y_lo`` subject to
``M^T y = 0``, ``a^T y + y_hi - y_lo = 1``, ``y >= 0``: a standard-form LP with only
``d + 1`` equality rows, which always has the feasible basis ``y_hi = 1`` (with ``d``
artificial columns held at zero). A revised primal simplex on it with Bland's rule
(the smallest index enters; among ties of the ratio test the smallest index leaves)
cannot cycle in exact arithmetic, so it is finite and exact up to the rounding of its
``(d + 1) x (d + 1)`` basis solves. Its simplex multipliers are ``(t, s)`` itself; a
dual ray (no blocking row) proves that no ``(t, s)`` exists. No scipy LP, no time
limit. The simplex runs in the compiled kernel (``src/kernel/scale_lp.cpp``); this module
reduces the step to the LP and maps the answer back.

A row enters only when the multipliers violate it by more than they are known to: by
more than :data:`PRICE_TOL` ``(1 + |g_j|)`` (units of ``x``: the rows are unit-norm in
``x``), and by more than the rounding ``eps cond_1(B) |pi|_1 |E_j|_1`` that the
basis ``B`` puts on the multipliers ``pi``. Degenerate steps need both: when ``x = 0``
is infeasible the optimum is often a vertex where a pinned variable's two bounds, two
opposite rows (a single feasible scale) or nearly parallel rows meet, and there a
violation of 1e-12 is rounding (the opposite row then finds no pivot: a "ray" of
rounding that called the step infeasible), and a basis of nearly opposite rows has a
condition of 1e8 or more, whose multipliers carry 1e-9 of rounding (entering on it
cycled to the iteration limit). The point returned meets every row to about that:
within 1e-9 where the largest scale is well-posed; within 1e-7, with the scale within
1e-7 of the largest, where rows less than 1e-7 from opposite meet at the optimum (there
a violation of 1e-9 moves the largest scale by up to a tenth, for any solver).

When ``A`` is rank-deficient (at :data:`~._affine.RANK_RTOL`) and ``direction`` has a
part outside its range, only the one ``s`` that cancels that part can be feasible
(usually ``s = 0``): the scale is then limited by **rank**, not by a bound
(:attr:`TaskScale.rank_limited`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .._compiled import kernel
from ..step.problem import StepProblem
from ._affine import CONSISTENCY_TOL, problem_basis

FloatArray = NDArray[np.float64]

#: A largest feasible task scale at least ``1 - FEASIBLE_SCALE_TOL`` is the full task:
#: the one constant by which every caller decides "the full task is feasible". The
#: residual it leaves, ``FEASIBLE_SCALE_TOL |b_ff|``, is far below the 1e-7 of the
#: verification tolerance.
FEASIBLE_SCALE_TOL = 1e-9

#: A row violated by at most ``PRICE_TOL (1 + |g_j|)`` [units of x, unit-norm rows]
#: counts as met: a reduced cost (primal slack) above minus that does not enter (1e-9,
#: the size of :data:`~.certify.ACTIVE_TOL`; defined in
#: ``src/kernel/constants.hpp``).
PRICE_TOL: float = kernel.PRICE_TOL

#: Pivot elements below this share of the column's largest entry are never pivoted on
#: (1e-11, defined in ``src/kernel/constants.hpp``).
PIVOT_TOL: float = kernel.PIVOT_TOL


@dataclass(frozen=True)
class TaskScale:
    """Largest feasible scale of a task.

    Attributes
    ----------
    scale : float or None
        The largest ``s`` in ``[0, cap]`` with a feasible ``x``; None when no ``s``
        in ``[0, cap]`` has one.
    x : ndarray or None
        A feasible point at ``s = scale`` (clipped to the box).
    blocking : tuple of str
        The bounds and rows that stop ``s`` from growing (at ``scale < cap``), or, when
        ``scale`` is None, rows that admit no common point.
    rank_limited : bool
        ``direction`` has a part outside the numerical range of ``A``: the scale is held
        by the rank of the step, not by a bound.
    """

    scale: float | None
    x: FloatArray | None
    blocking: tuple[str, ...]
    rank_limited: bool = False

    @property
    def full(self) -> bool:
        """Whether the full task (``s = 1``) is feasible (to :data:`FEASIBLE_SCALE_TOL`)."""
        return self.scale is not None and self.scale >= 1.0 - FEASIBLE_SCALE_TOL


def max_task_scale(problem: StepProblem, cap: float = 1.0) -> TaskScale:
    """Largest ``s`` in ``[0, cap]`` with ``A x = s b`` inside every limit."""
    return max_scale(problem, np.zeros(problem.m), problem.b, cap)


def max_scale(problem: StepProblem, base: FloatArray, direction: FloatArray,
              cap: float = 1.0) -> TaskScale:
    """Largest ``s`` in ``[0, cap]`` such that ``A x = base + s direction`` meets the limits.

    Parameters
    ----------
    problem : StepProblem
        Supplies ``A``, the boxes and the rows (its own ``b`` is not read).
    base, direction : ndarray, shape (m,)
        The right-hand side at ``s = 0`` and its rate of change [m/s; rad/s].
    cap : float
        Largest scale of interest.

    Returns
    -------
    TaskScale
    """
    if problem.has_empty_box():
        return TaskScale(None, None, problem.empty_bounds())
    A = problem.A
    f = problem_basis(problem)  # the exact solver's basis of A (P formed here)
    P = f.P
    x_b, x_d = P @ base, P @ direction
    s_lo, s_hi = 0.0, float(cap)
    rank_limited = False
    if f.rank < problem.m:
        r_b, r_d = base - A @ x_b, direction - A @ x_d
        tol_b = CONSISTENCY_TOL * max(1.0, float(np.abs(base).max(initial=0.0)),
                                      _size(f, x_b))
        tol_d = CONSISTENCY_TOL * max(1.0, float(np.abs(direction).max(initial=0.0)),
                                      _size(f, x_d))
        if float(np.abs(r_d).max(initial=0.0)) > tol_d:
            rank_limited = True
            s_fix = -float(r_b @ r_d) / float(r_d @ r_d)
            if (float(np.abs(r_b + s_fix * r_d).max()) > tol_b + s_fix * tol_d
                    or not -FEASIBLE_SCALE_TOL <= s_fix <= cap + FEASIBLE_SCALE_TOL):
                return TaskScale(None, None, (), rank_limited=True)
            s_lo = s_hi = min(max(s_fix, 0.0), cap)
        elif float(np.abs(r_b).max(initial=0.0)) > tol_b:
            return TaskScale(None, None, ())  # the feedback alone is out of reach
    ineq = problem.inequalities()
    C, e = ineq.C, ineq.e
    N = f.N
    M = C @ N
    a = C @ x_d
    g = e - C @ x_b
    found = _lp(M, a, g, s_lo, s_hi)
    if found is None:
        return TaskScale(None, None, (), rank_limited=rank_limited)
    ok, t, s, rows = found
    labels = ineq.labels(rows)
    if not ok:
        return TaskScale(None, None, labels, rank_limited=rank_limited)
    s = min(max(s, s_lo), s_hi)
    x = np.clip(x_b + s * x_d + N @ t, problem.lower, problem.upper)
    blocking = labels if s < cap - FEASIBLE_SCALE_TOL else ()
    return TaskScale(s, x, blocking, rank_limited=rank_limited)


def _size(f: kernel.Basis, x: FloatArray) -> float:
    """``sigma_max |x|``: the scale of ``A x`` (a rank-deficient ``A``: the SVD's sigma)."""
    return f.sigma_max * float(np.abs(x).max(initial=0.0)) if f.rank else 0.0


def _lp(M: FloatArray, a: FloatArray, g: FloatArray, s_lo: float, s_hi: float
        ) -> tuple[bool, FloatArray, float, list[int]] | None:
    """Maximise ``s`` s.t. ``M t + a s <= g``, ``s_lo <= s <= s_hi`` (see the module docs).

    Solved in the compiled kernel (``src/kernel/scale_lp.cpp``). Returns ``(feasible,
    t, s, rows)``: at the optimum, the rows of the final basis (the active rows that
    hold ``s``); when infeasible, the rows of the dual ray. None when the iteration
    limit is reached (never seen; reported, not guessed).
    """
    r = kernel.scale_lp(M, a, g, s_lo, s_hi)
    if r.status == _LP_LIMIT:
        return None
    return r.status == _LP_OPTIMAL, r.t, r.s, r.rows


#: The kernel's status codes of the LP.
_LP_OPTIMAL, _LP_INFEASIBLE, _LP_LIMIT = 0, 1, 2


__all__ = ["FEASIBLE_SCALE_TOL", "TaskScale", "max_scale", "max_task_scale"]
