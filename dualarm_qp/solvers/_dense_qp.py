"""A small dense strictly convex QP with inequality rows: the dual method of Goldfarb-Idnani.

    minimise    1/2 |R (t - t_free)|^2        (R upper triangular, invertible)
    subject to  M t <= f

The dual active-set method of Goldfarb and Idnani ("A numerically stable dual method for
solving strictly convex quadratic programs", Math. Programming 27, 1983) starts at the
unconstrained minimiser ``t_free`` and adds violated rows one at a time, dropping a row
of the working set when its multiplier would turn negative. It needs no feasible start,
detects an infeasible problem (a violated row that the working set cannot reach) and,
in exact arithmetic, terminates: every full step increases the dual objective strictly,
and between two full steps only rows are dropped.

The exact solver runs it in the null-space coordinates of the step (a handful of
variables, see :mod:`.nullspace`), the relax policy in the full ``x``.

Stated rules (so that the answer does not depend on the machine):

* a row is violated when ``M_i t - f_i > feas_tol`` (rows are unit-norm: the tolerance
  is in units of ``t``); the most violated row is added, the lowest index among rows
  whose violations agree to 1e-14 relative (no cycling on ties);
* a new row is linearly dependent on the working set when the part of its normal
  outside the working set's span is at most :data:`~._affine.RANK_RTOL` of the whole
  (in the metric of ``R``);
* a multiplier is blocking when its step ratio is positive beyond
  ``RANK_RTOL * max |r|``; ties go to the lowest position in the working set;
* at most ``max_iter`` additions and drops (ERROR beyond, never a wrong answer).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.linalg import lapack

from ._affine import RANK_RTOL

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class DenseQPResult:
    """Outcome of :func:`solve_dense_qp`.

    Attributes
    ----------
    status : {"optimal", "infeasible", "max_iter"}
        What happened.
    t : ndarray, shape (d,)
        The minimiser (optimal), or the last iterate.
    active : ndarray of int
        Rows of the working set at the end (for "infeasible": the rows that, with
        ``blocking``, admit no common point).
    multipliers : ndarray
        Their multipliers (``>= 0``): ``R^T R (t - t_free) + M_A^T u = 0``.
    blocking : int
        The violated row that could not be added ("infeasible"), else -1.
    iterations : int
        Additions and drops performed.
    """

    status: str
    t: FloatArray
    active: NDArray[np.intp]
    multipliers: FloatArray
    blocking: int
    iterations: int


def solve_dense_qp(R: FloatArray, t_free: FloatArray, M: FloatArray, f: FloatArray, *,
                   feas_tol: float = 1e-10, max_iter: int | None = None) -> DenseQPResult:
    """Minimise ``1/2 |R (t - t_free)|^2`` subject to ``M t <= f``.

    Parameters
    ----------
    R : ndarray, shape (d, d)
        Upper triangular, invertible: the Hessian is ``R^T R``.
    t_free : ndarray, shape (d,)
        The unconstrained minimiser.
    M : ndarray, shape (k, d)
        Inequality rows (unit norm, or zero rows).
    f : ndarray, shape (k,)
        Their right-hand sides (finite).
    feas_tol : float
        Violation below which a row counts as met (units of ``t``).
    max_iter : int, optional
        Limit on additions and drops (default ``10 (k + d) + 10``).

    Returns
    -------
    DenseQPResult
    """
    d = t_free.shape[0]
    k = M.shape[0]
    limit = 10 * (k + d) + 10 if max_iter is None else max_iter
    # J0 = R^-1, so that J0 J0^T = (R^T R)^-1: the inverse Hessian, factored.
    J0 = _upper_solve(R, np.eye(d)) if d else np.zeros((0, 0))
    t = t_free.astype(np.float64, copy=True)
    active: list[int] = []
    u: list[float] = []
    iterations = 0
    while True:
        if k == 0:
            break
        viol = M @ t - f
        viol[active] = -np.inf
        worst = float(viol.max())
        if not worst > feas_tol:
            break
        # Most violated, lowest index among ties (stated anti-cycling rule).
        p = int(np.flatnonzero(viol >= worst - 1e-14 * max(1.0, abs(worst)))[0])
        n_p = M[p]
        u_p = 0.0
        while True:
            iterations += 1
            if iterations > limit:
                return _result("max_iter", t, active, u, -1, iterations)
            J1, J2, Ra = _split(J0, M, active)
            v = J0.T @ n_p
            w2 = J2.T @ n_p
            z = J2 @ w2
            r = _upper_solve(Ra, J1.T @ n_p) if active else np.zeros(0)
            # Partial step: the largest dual step keeping every multiplier >= 0.
            t1, drop = np.inf, -1
            if r.size:
                r_tol = RANK_RTOL * float(np.abs(r).max())
                for j, (rj, uj) in enumerate(zip(r.tolist(), u, strict=True)):
                    if rj > r_tol and uj / rj < t1:
                        t1, drop = uj / rj, j
            # Full step: the primal step that makes row p active.
            dependent = float(w2 @ w2) <= (RANK_RTOL ** 2) * float(v @ v)
            s_p = float(n_p @ t - f[p])  # > 0: violated
            t2 = np.inf if dependent else s_p / float(z @ n_p)
            if t1 == np.inf and t2 == np.inf:
                return _result("infeasible", t, active, u, p, iterations)
            if t2 == np.inf:  # step in the dual only, then drop the blocking row
                u = [uj - t1 * rj for uj, rj in zip(u, r.tolist(), strict=True)]
                u_p += t1
                del active[drop], u[drop]
                continue
            step = min(t1, t2)
            t = t - step * z
            u = [uj - step * rj for uj, rj in zip(u, r.tolist(), strict=True)]
            u_p += step
            if step >= t2:
                active.append(p)
                u.append(u_p)
                break
            del active[drop], u[drop]
    return _result("optimal", t, active, u, -1, iterations)


def _upper_solve(R: FloatArray, B: FloatArray) -> FloatArray:
    """``R^-1 B`` for an upper triangular ``R`` (LAPACK ``dtrtrs``, no checks: tiny sizes)."""
    x, info = lapack.dtrtrs(R, B, lower=0)
    if info != 0:  # a zero on the diagonal: the rows were dependent (never chosen so)
        return np.asarray(np.linalg.lstsq(R, B, rcond=None)[0], dtype=np.float64)
    return np.asarray(x, dtype=np.float64)


def _split(J0: FloatArray, M: FloatArray, active: list[int]
           ) -> tuple[FloatArray, FloatArray, FloatArray]:
    """``J = J0 Q`` split as ``[J1 J2]`` and ``R_a``, from ``J0^T N_A = Q [R_a; 0]``."""
    d = J0.shape[0]
    q = len(active)
    if not q:
        return np.zeros((d, 0)), J0, np.zeros((0, 0))
    B = J0.T @ M[active].T
    Q, Ra = np.linalg.qr(B, mode="complete")
    J = J0 @ Q
    return J[:, :q], J[:, q:], Ra[:q]


def _result(status: str, t: FloatArray, active: list[int], u: list[float], blocking: int,
            iterations: int) -> DenseQPResult:
    return DenseQPResult(status, t, np.asarray(active, dtype=np.intp),
                         np.maximum(np.asarray(u, dtype=np.float64), 0.0), blocking,
                         iterations)


__all__ = ["DenseQPResult", "solve_dense_qp"]
