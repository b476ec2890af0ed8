"""Geometry of the step's equality ``A x = b`` and of its feasible set (private).

Two tools shared by the exact solver, the KKT certificate and the infeasible-step
policies:

* :func:`affine_solutions` writes every solution of ``A x = b`` as ``x0 + N t``;
* :func:`max_task_scale` finds the largest ``s`` for which ``A x = s b`` meets the box,
  in closed form when the null space has at most one dimension (the paper's step,
  and the leader's square 6 x 6 step) and with a linear program otherwise.

Every decision about a dimension in :mod:`.nullspace`, :mod:`._kkt` and here (the rank
of ``A`` or of a column subset of it, hence the null-space dimension; whether a
variable moves along a null direction) is taken from a singular value decomposition
with the one relative tolerance :data:`RANK_RTOL`. None rests on an LU pivot, on the
``info`` of a LAPACK solve, or on a machine-dependent default cut-off, so the decided
dimension is the same on every CPU and BLAS build unless a singular value lies within
rounding (about 1e-15 relative) of the cut-off.
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

#: Relative rank tolerance (dimensionless). A singular value ``sigma_i`` of ``A`` with
#: ``sigma_i <= RANK_RTOL * sigma_1`` is zero: its direction belongs to the null space.
#: Dropping it is a backward perturbation of ``A`` of at most ``RANK_RTOL * ||A||_2``,
#: the same relative size as :data:`CONSISTENCY_TOL` and far inside the 1e-7 of
#: ``base.Tolerance``; it is also 1e6 times the rounding of a double-precision SVD
#: (about ``n * eps * sigma_1``, 1.6e-15 for n = 7), so rounding noise, LU-pivot-sized
#: residues (1e-17) and perturbations up to 1e-10 never change the decision. A step is
#: called full rank only if no direction of ``x`` is amplified by more than 1e9 / ||A||
#: into ``x0``. The same number decides when a null direction "does not move" a
#: variable (a component ``|z_i| <= RANK_RTOL * max |z|`` of a unit null vector is zero).
RANK_RTOL = 1e-9

#: Relative residual above which ``A x = b`` is called inconsistent (rank-deficient ``A``
#: and ``b`` outside its numerical range): ``max |A x0 - b| > CONSISTENCY_TOL *
#: max(1, max |b|, sigma_1 max |x0|)`` for the minimum-norm ``x0`` (dimensionless; the
#: same size as :data:`RANK_RTOL`, whose truncation it must tolerate).
CONSISTENCY_TOL = 1e-9


@dataclass(frozen=True, slots=True)
class Factor:
    """Rank-revealing (singular value) decomposition of an ``m x n`` matrix ``A``.

    Only the numerical range and null space are kept: ``A ~= U diag(sigma) V^T`` with
    the singular values at or below :data:`RANK_RTOL` times the largest dropped.

    Attributes
    ----------
    U : ndarray, shape (m, r)
        Orthonormal basis of the numerical range of ``A`` (r = numerical rank).
    sigma : ndarray, shape (r,)
        The kept singular values, decreasing (units of ``A``).
    V : ndarray, shape (n, r)
        Orthonormal basis of the numerical row space of ``A``.
    N : ndarray, shape (n, n - r)
        Orthonormal basis of the numerical null space of ``A``.
    """

    U: FloatArray
    sigma: FloatArray
    V: FloatArray
    N: FloatArray

    @property
    def rank(self) -> int:
        """Numerical rank ``r`` of ``A`` (at tolerance :data:`RANK_RTOL`)."""
        return int(self.sigma.size)

    @property
    def nullity(self) -> int:
        """Numerical null-space dimension ``n - r``."""
        return int(self.N.shape[1])

    def solve(self, b: FloatArray) -> FloatArray:
        """Minimum-norm least-squares solution of ``A x = b`` (truncated pseudoinverse)."""
        return self.V @ ((self.U.T @ b) / self.sigma)

    def solve_transposed(self, g: FloatArray) -> FloatArray:
        """Minimum-norm least-squares solution of ``A^T y = g`` (truncated pseudoinverse)."""
        return self.U @ ((self.V.T @ g) / self.sigma)


def factor(A: FloatArray) -> Factor:
    """Singular value decomposition of ``A`` truncated at :data:`RANK_RTOL`.

    Parameters
    ----------
    A : ndarray, shape (m, n)
        Any real matrix (m or n may be 0).

    Returns
    -------
    Factor
        Range, kept singular values, row space and null space of ``A``.
    """
    m, n = A.shape
    if m == 0 or n == 0:
        return Factor(np.zeros((m, 0)), np.zeros(0), np.zeros((n, 0)), np.eye(n))
    # LAPACK dgesvd directly: a third cheaper than np.linalg.svd at 6 x 7. Its info is
    # only a convergence flag (never a rank decision); np.linalg.svd raises on failure.
    U, sv, Vt, info = lapack.dgesvd(A, compute_uv=1, full_matrices=1)
    if info != 0:
        U, sv, Vt = np.linalg.svd(A, full_matrices=True)
    cut = RANK_RTOL * float(sv[0])
    rank = sum(1 for s in sv.tolist() if s > cut)  # sv[0] = 0: rank 0
    return Factor(U[:, :rank], sv[:rank], Vt[:rank].T, Vt[rank:].T.copy())


def moves(z: FloatArray) -> NDArray[np.bool_]:
    """Components of a null direction ``z`` that move their variable.

    ``|z_i| <= RANK_RTOL * max |z|`` counts as zero: setting it to zero perturbs ``A z``
    by at most ``RANK_RTOL * max |z| * ||a_i||``, the backward error of the rank decision.
    """
    return np.abs(z) > RANK_RTOL * float(np.abs(z).max(initial=0.0))


def least_distance(N: FloatArray, x0: FloatArray, w: FloatArray, c: FloatArray
                   ) -> FloatArray:
    """Minimiser of ``sum w_i (x_i - c_i)^2`` over ``x = x0 + N t``.

    ``N`` has orthonormal columns and ``w > 0``, so ``W^1/2 N`` has full column rank
    (its singular values lie in ``[min sqrt(w), max sqrt(w)]``): no rank decision, one
    Householder QR solve of ``min |W^1/2 (x0 + N t - c)|`` (not the normal equations,
    whose condition is the square of that, up to 1e9 with a sliding weight of 1e9).

    Parameters
    ----------
    N : ndarray, shape (n, d)
        Orthonormal null-space basis (``d = 0`` returns ``x0``).
    x0 : ndarray, shape (n,)
        A point of the affine set (units of ``x``).
    w : ndarray, shape (n,)
        Positive weights.
    c : ndarray, shape (n,)
        Centre (units of ``x``).
    """
    if not N.shape[1]:
        return x0
    root = np.sqrt(w)
    Q, R = np.linalg.qr(root[:, None] * N)
    t = np.linalg.solve(R, Q.T @ (root * (c - x0)))
    return np.asarray(x0 + N @ t, dtype=np.float64)


@dataclass(frozen=True, slots=True)
class AffineSet:
    """All solutions ``x = x0 + N t`` of ``A x = b``.

    Attributes
    ----------
    x0 : ndarray, shape (n,)
        The minimum-norm solution (same units as ``x``); orthogonal to ``N``, so
        ``|x0| <= |x|`` for every solution ``x`` (no cancellation in ``x0 + N t``).
    N : ndarray, shape (n, d)
        Orthonormal basis of the numerical null space of ``A`` (d = n - rank A, the
        rank decided with :data:`RANK_RTOL`); ``d = 0`` for a nonsingular square ``A``.
    factor : Factor
        The decomposition of ``A`` it came from (for multipliers, ``A^T y = g``).
    """

    x0: FloatArray
    N: FloatArray
    factor: Factor

    @property
    def nullity(self) -> int:
        """Null-space dimension ``d``."""
        return int(self.N.shape[1])


def affine_solutions(A: FloatArray, b: FloatArray) -> AffineSet | None:
    """Parametrise the solutions of ``A x = b`` as ``x0 + N t``.

    One truncated SVD (:func:`factor`): the rank is the number of singular values above
    ``RANK_RTOL * sigma_1``, ``x0`` is the minimum-norm solution and ``N`` the trailing
    right singular vectors. About 30 us for the 12 x 13 step of the PUMA pair.

    Parameters
    ----------
    A : ndarray, shape (m, n)
        Equality matrix (units of ``b`` per unit of ``x``).
    b : ndarray, shape (m,)
        Right-hand side [m/s; rad/s].

    Returns
    -------
    AffineSet or None
        None when ``A x = b`` has no solution: ``max |A x0 - b|`` exceeds
        ``CONSISTENCY_TOL * max(1, max |b|)`` (``A`` rank-deficient, ``b`` outside its
        numerical range).
    """
    f = factor(A)
    x0 = f.solve(b)
    # Full row rank: every b is in the range, the residual is rounding only.
    if f.rank < A.shape[0] and not _consistent(A, b, f, x0):
        return None
    return AffineSet(x0, f.N, f)


def _consistent(A: FloatArray, b: FloatArray, f: Factor, x0: FloatArray) -> bool:
    """Whether ``x0`` solves ``A x = b`` to :data:`CONSISTENCY_TOL` (backward error).

    The residual is measured against ``max(1, max |b|, sigma_1 max |x0|)``: the rank
    decision may leave ``RANK_RTOL * sigma_1 |x|`` of ``b`` unmatched, which is scaled
    by the size of ``A x``, not only by that of ``b``.
    """
    scale = max(1.0, float(np.abs(b).max()),
                float(f.sigma[0]) * float(np.abs(x0).max()) if f.rank else 0.0)
    return float(np.abs(A @ x0 - b).max()) <= CONSISTENCY_TOL * scale


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

    Exact closed form when the numerical null space (:data:`RANK_RTOL`) has at most one
    dimension (see :func:`_scale_1d`): a 6 x 7 step, or a square 6 x 6 step, where
    ``x = s x0`` and ``s`` is limited by the first bound ``s x0`` meets. A HiGHS linear
    program in ``(x, s)`` on the numerical range of ``A`` otherwise (:func:`_scale_lp`).

    Parameters
    ----------
    problem : StepProblem
        The step; ``b`` in [m/s; rad/s], bounds in [rad/s, m/s].
    cap : float
        Largest scale of interest (dimensionless).

    Returns
    -------
    TaskScale
        The scale, a point at that scale and the bounds that block it.
    """
    if (problem.lower > problem.upper).any():
        return TaskScale(None, None, problem.empty_bounds())
    aff = affine_solutions(problem.A, problem.b)
    if aff is not None and aff.nullity <= 1:
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
    z = aff.N[:, 0] if aff.nullity else np.zeros_like(x0)
    lower, upper = problem.lower, problem.upper
    move = moves(z)  # all False for a square nonsingular A (no null direction)
    fixed = np.flatnonzero(~move)
    idx = np.flatnonzero(move)
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
    """Task scale by linear programming: maximise s s.t. A x - s b = 0, box, 0 <= s <= cap.

    The equality is written on the numerical range of ``A`` (:func:`factor`):
    ``diag(sigma) V^T x - s U^T b = 0``, full row rank, so that HiGHS takes no rank
    decision of its own. The part of ``b`` outside that range, when it exceeds
    ``CONSISTENCY_TOL`` (``A x = b`` inconsistent), adds the row ``|b_perp| s = 0``.
    """
    n = problem.n
    f = factor(problem.A)
    b_r = f.U.T @ problem.b
    rows = [np.hstack([f.V.T * f.sigma[:, None], -b_r[:, None]])]
    if problem.m and not _consistent(problem.A, problem.b, f, f.solve(problem.b)):
        b_perp = float(np.linalg.norm(problem.b - f.U @ b_r))
        rows.append(np.hstack([np.zeros(n), [b_perp]])[None, :])
    A_eq = np.vstack(rows)
    cost = np.zeros(n + 1)
    cost[n] = -1.0
    bounds = [(_finite_or_none(lo), _finite_or_none(up))
              for lo, up in zip(problem.lower, problem.upper, strict=True)] + [(0.0, float(cap))]
    res = linprog(cost, A_eq=A_eq if A_eq.shape[0] else None,
                  b_eq=np.zeros(A_eq.shape[0]) if A_eq.shape[0] else None,
                  bounds=bounds, method="highs",
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
