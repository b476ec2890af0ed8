"""Geometry of the step's equality ``A x = b`` and of its feasible set (private).

Two tools shared by the exact solver, the SNS solver and the infeasible-step policies:

* :func:`affine_solutions` writes every solution of ``A x = b`` as ``x0 + N t``;
* :func:`max_task_scale` finds the largest ``s`` for which ``A x = s b`` meets the box,
  in closed form when the null space is one-dimensional (the paper's 6 x 7 step) and
  with a linear program otherwise.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.linalg import lapack
from scipy.optimize import linprog

from ..step.problem import StepProblem
from ._util import bound_label

FloatArray = NDArray[np.float64]

#: Largest ``max|x0| / max|x|`` accepted from the pivoted factorisation before the SVD is
#: used instead: beyond it ``x = x0 + t z`` cancels and loses more than 6 digits.
PIVOT_GROWTH_LIMIT = 1e6

#: Relative residual above which ``A x = b`` is called inconsistent (rank-deficient ``A``).
CONSISTENCY_TOL = 1e-9


@dataclass(frozen=True, slots=True)
class AffineSet:
    """All solutions ``x = x0 + N t`` of ``A x = b``.

    Attributes
    ----------
    x0 : ndarray, shape (n,)
        One solution (same units as ``x``).
    N : ndarray, shape (n, d)
        Basis of the null space of ``A`` (d = n - rank A), not necessarily orthonormal.
    pivoted : bool
        True when it came from the fast pivoted solve (``x0`` may then be large), False
        when it came from the SVD (``x0`` is the minimum-norm solution, orthogonal to N).
    """

    x0: FloatArray
    N: FloatArray
    pivoted: bool


def affine_solutions(A: FloatArray, b: FloatArray, *, robust: bool = False
                     ) -> AffineSet | None:
    """Parametrise the solutions of ``A x = b``.

    For an ``m x (m+1)`` matrix (one redundant variable, as in Eq. 25), and unless
    ``robust`` is set, the last column is the pivot: one LU solve of
    ``A[:, :m] [w, x0] = [a_last, b]`` gives ``z = [-w, 1]`` and ``x0 = [x0, 0]``.
    If that block is singular, or for any other shape, the SVD of ``A`` is used. The
    pivoted result may be inaccurate (large ``x0``, even non-finite) when the block is
    nearly singular: callers check it and retry with ``robust=True``.

    Returns
    -------
    AffineSet or None
        None when ``A x = b`` has no solution (``A`` rank-deficient and ``b`` outside its
        range).
    """
    m, n = A.shape
    if n == m + 1 and not robust:
        # LAPACK gesv directly: np.linalg.solve costs twice as much at this size. The
        # right-hand sides [a_last, b] are stacked as rows and transposed, which gives
        # the column-major array gesv works on without a copy.
        sol, info = lapack.dgesv(A[:, :m], np.array((A[:, m], b)).T)[2:]
        if info == 0:  # info > 0: the block is exactly singular
            w, x0 = sol.T.tolist()  # at this size building from lists beats slicing
            z = [-wi for wi in w]
            z.append(1.0)
            return AffineSet(np.array([*x0, 0.0]), np.array(z)[:, None], True)
    U, sv, Vt = np.linalg.svd(A, full_matrices=True)
    rank = int(np.count_nonzero(sv > max(m, n) * np.finfo(float).eps * sv[0])) if m else 0
    x0 = Vt[:rank].T @ ((U[:, :rank].T @ b) / sv[:rank])
    scale = max(1.0, float(np.abs(b).max(initial=0.0)))
    if m and float(np.abs(A @ x0 - b).max()) > CONSISTENCY_TOL * scale:
        return None
    return AffineSet(x0, Vt[rank:].T.copy(), False)


@dataclass(frozen=True, slots=True)
class TaskScale:
    """Largest feasible scale of the task.

    Attributes
    ----------
    scale : float or None
        Largest ``s`` in ``[0, cap]`` with ``{A x = s b, lower <= x <= upper}`` non-empty;
        None when even ``s = 0`` is infeasible.
    x : ndarray or None
        A point of that set at ``s = scale``.
    blocking : tuple of str
        Bounds that stop ``s`` from growing further (empty when ``scale == cap``).
    """

    scale: float | None
    x: FloatArray | None
    blocking: tuple[str, ...]


def max_task_scale(problem: StepProblem, cap: float = 1.0) -> TaskScale:
    """Largest ``s`` in ``[0, cap]`` such that ``A x = s b`` has a solution in the box.

    Exact closed form for a one-dimensional null space (see :func:`_scale_1d`); a
    HiGHS linear program in ``(x, s)`` otherwise.
    """
    if (problem.lower > problem.upper).any():
        return TaskScale(None, None, problem.empty_bounds())
    aff = affine_solutions(problem.A, problem.b, robust=True)
    if aff is not None and aff.N.shape[1] <= 1:
        return _scale_1d(problem, aff, cap)
    return _scale_lp(problem, cap)


def _scale_1d(problem: StepProblem, aff: AffineSet, cap: float) -> TaskScale:
    """Closed-form task scale for ``x = s x0 + t z`` (at most one null direction).

    Each bound ``l_i <= s x0_i + t z_i <= u_i`` with ``z_i != 0`` bounds ``t`` between
    lines in ``s``: ``t >= L_j(s)`` and ``t <= U_k(s)``. The feasible ``s`` are the
    intersection of the half-lines ``L_j(s) <= U_k(s)`` over all pairs (j, k), with
    ``l_i <= s x0_i <= u_i`` for the bounds with ``z_i = 0``, and with ``[0, cap]``.
    Every such condition reads ``coef * s <= rhs``.
    """
    x0 = aff.x0
    z = aff.N[:, 0] if aff.N.shape[1] else np.zeros_like(x0)
    lower, upper = problem.lower, problem.upper
    moving = np.abs(z) > 1e-13 * float(np.abs(z).max(initial=0.0))
    fixed = np.flatnonzero(~moving)
    idx = np.flatnonzero(moving)
    zi, xi = z[idx], x0[idx]
    pos = zi > 0
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        # t >= alpha + beta s (from the "lower" bound in t), t <= gamma + beta s.
        alpha = np.where(pos, lower[idx], upper[idx]) / zi
        gamma = np.where(pos, upper[idx], lower[idx]) / zi
        beta = -xi / zi
        coef = np.concatenate([x0[fixed], -x0[fixed],
                               (beta[:, None] - beta[None, :]).ravel()])
        rhs = np.concatenate([upper[fixed], -lower[fixed],
                              (gamma[None, :] - alpha[:, None]).ravel()])
    k = idx.size
    labels = ([(bound_label(problem, int(i), True),) for i in fixed]
              + [(bound_label(problem, int(i), False),) for i in fixed])

    def why(c: int) -> tuple[str, ...]:
        if c < len(labels):
            return labels[c]
        j, kk = divmod(c - len(labels), k)
        return (bound_label(problem, int(idx[j]), not pos[j]),
                bound_label(problem, int(idx[kk]), bool(pos[kk])))

    finite = np.isfinite(rhs)  # rhs = +inf: an infinite bound, never binds
    tiny = 1e-14 * np.maximum(1.0, np.abs(np.where(finite, rhs, 0.0)))
    flat = finite & (np.abs(coef) <= tiny)
    broken = np.flatnonzero(flat & (rhs < -1e-12))
    if broken.size:  # 0 <= rhs fails for every s
        return TaskScale(None, None, why(int(broken[0])))
    with np.errstate(divide="ignore", invalid="ignore"):
        limit = np.where(finite & ~flat, rhs / np.where(flat, 1.0, coef), np.nan)
    no_bound: tuple[str, ...] = ()
    ups = np.flatnonzero(coef > 0)
    ups = ups[np.isfinite(limit[ups])]
    downs = np.flatnonzero(coef < 0)
    downs = downs[np.isfinite(limit[downs])]
    s_hi, hi_why = float(cap), no_bound
    if ups.size and float(limit[ups].min()) < s_hi:
        c = int(ups[np.argmin(limit[ups])])
        s_hi, hi_why = float(limit[c]), why(c)
    s_lo, lo_why = 0.0, no_bound
    if downs.size and float(limit[downs].max()) > s_lo:
        c = int(downs[np.argmax(limit[downs])])
        s_lo, lo_why = float(limit[c]), why(c)
    if s_lo > s_hi + 1e-12 * max(1.0, abs(s_hi)) or s_hi < -1e-12:
        return TaskScale(None, None, lo_why + hi_why)
    s = max(s_hi, 0.0)
    t = 0.0
    if k:
        t = _midpoint(float(np.max(alpha + beta * s)), float(np.min(gamma + beta * s)))
    x = np.clip(s * x0 + t * z, lower, upper)
    return TaskScale(s, x, hi_why if s < cap else ())


def _midpoint(lo: float, hi: float) -> float:
    """Return a point of ``[lo, hi]`` (ends may be infinite), the midpoint if reversed."""
    if np.isfinite(lo) and np.isfinite(hi):
        return 0.5 * (lo + hi)
    if np.isfinite(lo):
        return lo
    if np.isfinite(hi):
        return hi
    return 0.0


def _scale_lp(problem: StepProblem, cap: float) -> TaskScale:
    """Task scale by linear programming: maximise s s.t. A x - s b = 0, box, 0 <= s <= cap."""
    n = problem.n
    cost = np.zeros(n + 1)
    cost[n] = -1.0
    bounds = [(_finite_or_none(lo), _finite_or_none(up))
              for lo, up in zip(problem.lower, problem.upper, strict=True)] + [(0.0, float(cap))]
    res = linprog(cost, A_eq=np.hstack([problem.A, -problem.b[:, None]]),
                  b_eq=np.zeros(problem.m), bounds=bounds, method="highs",
                  options={"primal_feasibility_tolerance": 1e-10,
                           "dual_feasibility_tolerance": 1e-10, "time_limit": 1.0})
    if res.status != 0 or res.x is None:
        return TaskScale(None, None, ())
    x = np.clip(res.x[:n], problem.lower, problem.upper)
    s = float(res.x[n])
    blocking: list[str] = []
    if s < cap:
        lo_dual = np.asarray(res.lower.marginals)[:n]
        up_dual = np.asarray(res.upper.marginals)[:n]
        blocking += [bound_label(problem, int(i), False) for i in np.flatnonzero(lo_dual > 1e-12)]
        blocking += [bound_label(problem, int(i), True) for i in np.flatnonzero(up_dual < -1e-12)]
    return TaskScale(s, x, tuple(blocking))


def _finite_or_none(value: float) -> float | None:
    return float(value) if np.isfinite(value) else None
