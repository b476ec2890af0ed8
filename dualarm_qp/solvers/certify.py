"""The one certification of a step's answer: feasibility, then optimality (KKT).

Every solver returns a *claim*: a status and an ``x``. :func:`certify` is the only
place that decides what the claim is worth, for every solver, with one feasibility
tolerance and one optimality check:

1. a non-finite or misshaped ``x`` is ERROR;
2. the equality ``A x = b`` must hold to ``tol.equality * max(1, max |b|)`` of the
   right-hand side the answer was asked for (the scaled one for a scaled task: the
   policy hands the solver the scaled problem), except for a RELAXED answer, which
   meets it in least squares by definition, and an ESCAPING move, which may leave it
   within a share of the error budget (:mod:`dualarm_qp.control.escape`);
3. every box and every (unit-norm) general row must hold to ``tol.bounds``;
   a usable claim that breaks 2 or 3 is VIOLATION (the reference step, which ignores
   the limits by design, is the common case);
4. an OPTIMAL claim must pass the KKT conditions (:func:`kkt_holds`); one that does
   not is FEASIBLE, never OPTIMAL. For the reference step (``claims_bounds=False``)
   OPTIMAL means "the minimiser of Eq. 37 over ``A x = b``" and stationarity is
   checked on the equality alone.

The KKT check does not trust the solver's multipliers or its working set: the active
set is read from ``x`` (every bound and row within :data:`ACTIVE_TOL` of binding, both
sides of a zero-width box), the exact minimiser on that active set is recomputed and
must lie within :data:`STEP_RTOL` of ``x``, and the multipliers are found by
non-negative least squares of the projected stationarity condition

    Z^T (W (x - c) + C_a^T mu) = 0,   mu >= 0

on the null space ``Z`` of ``A`` (rank at :data:`~._affine.RANK_RTOL`). Non-negative
least squares finds a valid multiplier vector whenever one exists, also on degenerate
vertices where the minimum-norm multipliers have the wrong sign (see
:func:`kkt_holds`).

The residuals and the KKT test are computed by the compiled kernel
(``src/kernel/certify.cpp``, with a Lawson-Hanson non-negative least squares); the
decisions below stay here.
"""

from __future__ import annotations

import math
import time
from dataclasses import replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._compiled import kernel
from ..step.problem import Inequalities, Names, StepProblem
from ._affine import cost_arrays, problem_basis
from .base import DEFAULT_TOLERANCE, Status, StepSolution, Tolerance

FloatArray = NDArray[np.float64]

#: Distance (units of ``x``, rows unit-norm) within which a bound or row is active.
ACTIVE_TOL: float = kernel.ACTIVE_TOL  # 1e-9, defined in src/kernel/constants.hpp

#: How far (relative to ``max(1, |x|)``, units of ``x``) a claimed optimum may lie from
#: the exact minimiser on its active set, and how long the Newton step to stationarity
#: may be.
STEP_RTOL: float = kernel.STEP_RTOL  # 1e-8

#: Rounding allowance of the stationarity check: a thousand ulps of the gradient's
#: largest term ``w_i (x_i - c_i)`` (with a sliding weight of 1e9 one ulp of the
#: sliding speed is already 1e-7 of gradient).
ROUNDING: float = kernel.ROUNDING  # 1e3 * machine epsilon


def residuals(problem: StepProblem, x: FloatArray) -> tuple[float, float]:
    """``(max |A x - b|, largest violation of a box or a unit-norm row)`` of ``x``."""
    eq, box, rows = _residuals(problem, x)
    return eq, max(box, rows)


def _residuals(problem: StepProblem, x: FloatArray) -> tuple[float, float, float]:
    """``max |A x - b|``, the largest box violation and :meth:`StepProblem.row_violation`."""
    r = kernel.residuals(problem.A, problem.b, problem.lower, problem.upper, problem.G,
                         problem.h, x)
    return r.eq, r.box, r.row


def equality_limit(problem: StepProblem, tol: Tolerance) -> float:
    """Largest ``|A x - b|`` component that meets the equality [m/s or rad/s]."""
    return tol.equality * max(1.0, float(np.abs(problem.b).max(initial=0.0)))


def certify(problem: StepProblem, claim: StepSolution, tol: Tolerance = DEFAULT_TOLERANCE,
            *, claims_bounds: bool = True) -> StepSolution:
    """Check a solver's claim against ``problem`` and return what it is worth.

    Parameters
    ----------
    problem : StepProblem
        The problem the answer was asked for.
    claim : StepSolution
        The solver's status and ``x``.
    tol : Tolerance
        The feasibility tolerances.
    claims_bounds : bool
        False for the paper's reference step, which ignores the limits: its breaches
        are VIOLATION and its optimality is over the equality alone.

    Returns
    -------
    StepSolution
        A copy with the residuals, the objective, the active bounds and rows and
        ``verified_with = tol``, and the status the certificate supports.
    """
    start = time.perf_counter()
    x = claim.x
    reading = None
    if isinstance(x, np.ndarray) and x.shape == (problem.n,) and x.dtype.kind in "fiu":
        x = np.asarray(x, dtype=np.float64)
        rows = kernel.inequalities(problem.lower, problem.upper, problem.G, problem.h)
        w_diag, w_full, root_full = cost_arrays(problem)
        ask = claim.status is Status.OPTIMAL  # only an optimum needs A's basis (KKT test)
        reading = kernel.certificate(
            problem.A, problem.b, problem.lower, problem.upper, problem.G, problem.h,
            problem_basis(problem) if ask else None, rows.C, rows.e,
            rows.kind, rows.index, w_diag, w_full, root_full,
            problem.center, x, claims_bounds, tol.equality, tol.bounds, ask)
    return verdict(problem, claim, x, reading, tol, claims_bounds, start)


def verdict(problem: StepProblem, claim: StepSolution, x: FloatArray, reading: Reading | None,
            tol: Tolerance, claims_bounds: bool, start: float) -> StepSolution:
    """Return what ``claim`` is worth from the kernel's reading of its ``x`` (the rules above).

    :func:`certify`'s decisions, for it and for the one kernel call that solves and
    certifies a step (:meth:`~.nullspace.NullspaceSolver.solve_certified`, whose
    ``reading`` is ``kernel.certificate``'s of ``x`` with the KKT test, for ``problem``,
    ``tol`` and ``claims_bounds``). Private to the solvers: a reading is trusted.

    Parameters
    ----------
    x : ndarray
        ``claim.x`` as float64 (``reading`` not None).
    reading : kernel.Certificate or None
        The kernel's certificate of ``x``; None for a misshaped ``x``.
    start : float
        ``time.perf_counter()`` when the certification began.
    """
    fields = verdict_fields(problem, claim.status, claim.message, x, reading, tol,
                            claims_bounds)
    if fields is None:
        n = problem.n
        zeros = np.zeros(n, dtype=bool)
        return replace(claim, x=np.zeros(n),
                       status=Status.ERROR if claim.status.usable else claim.status,
                       objective=math.nan, eq_residual=math.nan, bound_violation=math.nan,
                       active_lower=zeros, active_upper=zeros, verified_with=tol,
                       build_time=problem.build_time,
                       message=claim.message or "solver returned a non-finite or misshaped x")
    solve_time = claim.solve_time + (time.perf_counter() - start)
    if type(claim) is not StepSolution:  # a subclass keeps its type and its own fields
        return replace(claim, **fields, solve_time=solve_time)
    return StepSolution(**fields, solve_time=solve_time, scale=claim.scale,
                        solver=claim.solver, extras=claim.extras)


def verdict_fields(problem: StepProblem, status: Status, message: str, x: FloatArray,
                   reading: Reading | None, tol: Tolerance, claims_bounds: bool
                   ) -> dict[str, Any] | None:
    """Return the certified fields of a claim (``status``, ``message``, its ``x``), or None.

    The decisions of :func:`verdict`, on the claim's parts: for a solver that makes its
    certified answer in one piece (:meth:`~.nullspace.NullspaceSolver.solve_certified`
    for an optimum), without a claim object first. None: ``x`` is not finite (or
    ``reading`` is None), which :func:`verdict` answers from the claim.

    Returns
    -------
    dict or None
        ``x``, ``status``, ``objective``, ``eq_residual``, ``bound_violation``,
        ``active_lower``, ``active_upper``, ``build_time``, ``message``,
        ``verified_with``, ``row_violation`` and ``active_rows`` of the
        :class:`~.base.StepSolution`.
    """
    if reading is None or not reading.finite:
        return None
    eq, box, row, limit = reading.eq, reading.box, reading.row, reading.eq_limit
    if status.usable:
        if status is not Status.RELAXED and status is not Status.ESCAPING and eq > limit:
            status = Status.VIOLATION
            message = message or f"equality residual {eq:.3g} exceeds tolerance {limit:.3g}"
        elif max(box, row) > tol.bounds:
            status = Status.VIOLATION
            message = message or _worst_breach(problem, x, box >= row, claims_bounds)
        elif status is Status.OPTIMAL and reading.kkt != 1:  # not confirmed (or not computed)
            status = Status.FEASIBLE
            message = ((message + "; ") if message else "") + (
                "the optimality certificate (KKT) does not confirm the claimed optimum")
    active = reading.active_rows
    return dict(x=x, status=status, objective=reading.objective, eq_residual=eq,
                bound_violation=box, active_lower=reading.active_lower,
                active_upper=reading.active_upper,
                build_time=problem.build_time, message=message, verified_with=tol,
                row_violation=row, active_rows=_row_names(problem, active))


def _row_names(problem: StepProblem, active: list[int]) -> tuple[str, ...]:
    """Names of the general rows ``active`` (rows of ``G``, the certificate's), each once."""
    if not active:
        return ()
    names = problem.row_names
    return tuple(dict.fromkeys(names[j] for j in active))


def named_rows(problem: StepProblem, rows: kernel.Rows | None) -> Inequalities:
    """Return ``problem``'s inequalities with their names, made from the kernel's ``rows``.

    A solver hands on the kernel's rows (``kernel.inequalities``'s or
    ``kernel.solve_certified``'s) and they are named here only when a message needs
    their names; None: the problem's own
    (:meth:`~dualarm_qp.step.StepProblem.inequalities`).
    """
    if rows is None:
        return problem.inequalities()
    return Inequalities(rows.C, rows.e, rows.kind, rows.index,
                        Names(problem.names, problem.row_names, problem.lower_by,
                              problem.upper_by))


#: The kernel's certificate of one ``x`` (``kernel.certificate``'s answer): whether it is
#: finite, the equality, box and row residuals, the equality's limit, the KKT test (-1
#: not asked, 0 fails, 1 holds), the objective, the active lower and upper bounds, the
#: active rows.
Reading = kernel.Certificate


def _worst_breach(problem: StepProblem, x: FloatArray, box: bool, claims_bounds: bool
                  ) -> str:
    """One line naming the worst broken box or row."""
    tail = "" if claims_bounds else " (this method ignores the bounds)"
    if box:
        i = int(np.argmax(np.maximum(problem.lower - x, x - problem.upper)))
        return (f"{problem.names[i]} = {x[i]:.6g} outside "
                f"[{problem.lower[i]:.6g}, {problem.upper[i]:.6g}]{tail}")
    norms = np.linalg.norm(problem.G, axis=1)
    gap = (problem.G @ x - problem.h) / np.where(norms > 0.0, norms, 1.0)
    j = int(np.nanargmax(gap))
    return f"row {problem.row_names[j]} broken by {gap[j]:.3g}{tail}"


def kkt_holds(problem: StepProblem, x: FloatArray, *, bounds: bool = True) -> bool:
    """Whether ``x`` is the minimiser of the step QP, to :data:`STEP_RTOL` in ``x``.

    The test does not trust a solver's working set or multipliers. The limits active at
    ``x`` (within :data:`ACTIVE_TOL`; none with ``bounds=False``) are held as
    equalities with ``A x = b``, and the exact minimiser ``x*`` of Eq. 37 on that
    affine set is computed in the null-space coordinates of ``A`` (its factorisation
    is the problem's, shared with the solver). ``x`` passes when

    1. ``|x - x*| <= tol``: ``x`` is that minimiser, the equality met exactly (a
       residual inside the feasibility tolerance along a near-null direction of an
       ill-conditioned ``A`` can hide a large distance: it does not pass), and
    2. the active limits have multipliers of the right sign: the gradient at ``x*``
       on the null space of ``A`` is a non-negative combination of the active limits'
       normals, found by non-negative least squares (valid multipliers are found also
       at degenerate vertices, where the minimum-norm ones may have the wrong sign),
       with a residual whose Newton step in ``x`` is at most ``tol``.

    ``tol = STEP_RTOL max(1, |x|) + ROUNDING |W (x - c)| / lambda_min`` [units of
    ``x``]: the second term is the rounding of the gradient carried into a Newton step
    (``lambda_min``: the smallest curvature of Eq. 37 on the null space).

    Parameters
    ----------
    problem : StepProblem
        The step.
    x : ndarray, shape (n,)
        A point that meets the equality and (with ``bounds``) every limit.
    bounds : bool
        Include the boxes and rows (False: the minimiser over ``A x = b`` alone).
    """
    ineq = problem.inequalities()
    w_diag, w_full, root_full = cost_arrays(problem)
    return bool(kernel.kkt_holds(problem.A, problem.b, problem_basis(problem),
                                 ineq.C, ineq.e, w_diag, w_full, root_full, problem.center,
                                 x, bounds))


__all__ = ["ACTIVE_TOL", "certify", "equality_limit", "kkt_holds", "residuals"]
