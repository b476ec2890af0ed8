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
  whose violations agree to ``TIE_RTOL`` (1e-14) relative (no cycling on ties);
* a new row is linearly dependent on the working set when the part of its normal
  outside the working set's span is at most :data:`~._affine.RANK_RTOL` of the whole
  (in the metric of ``R``);
* a multiplier is blocking when its step ratio is positive beyond
  ``RANK_RTOL * max |r|``; ties go to the lowest position in the working set;
* at most ``max_iter`` additions and drops (ERROR beyond, never a wrong answer).

The method runs in the compiled kernel (``src/kernel/dense_qp.cpp``); this module is its
typed Python entry.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .._compiled import kernel

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
    r = kernel.dense_qp(R, t_free, M, f, feas_tol, -1 if max_iter is None else max_iter)
    return DenseQPResult(_STATUS[r.status], r.t, np.asarray(r.active, dtype=np.intp),
                         np.asarray(r.multipliers, dtype=np.float64), r.blocking,
                         r.iterations)


#: The kernel's status codes.
_STATUS = ("optimal", "infeasible", "max_iter")


__all__ = ["DenseQPResult", "solve_dense_qp"]
