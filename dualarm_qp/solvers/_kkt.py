"""Active-set refinement of an approximate step QP answer (private).

First-order and interior-point backends stop at a tolerance; on the recorded steps the
sliding weight ``s7`` reaches 1e9, the multipliers reach 1e5 and more, and their
absolute dual tolerances cannot be met (see ``docs/benchmarks.md``). The backend's point
still tells which limits are active. Given that guess, the step QP reduces to an
equality-constrained least-distance problem (:func:`~._affine.least_distance_eq`, the
one kernel), solved exactly; the candidate is kept when it is feasible and passes the
one optimality check of the package (:func:`~.certify.kkt_holds`). This is what OSQP's
own "polish" does, done here once for every backend, in the original variables, for
boxes and general rows alike.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..step.problem import StepProblem
from ._affine import least_distance_eq
from .certify import kkt_holds

FloatArray = NDArray[np.float64]

#: Distances (units of ``x``, relative to ``max(1, |e_i|)``) under which a limit is
#: guessed active, tried in order.
ACTIVE_GUESSES = (1e-9, 1e-6, 1e-4)

#: Largest violation of a limit (relative to ``max(1, |e_i|)``) accepted of a candidate.
PRIMAL_TOL = 1e-10


def refine(problem: StepProblem, x: FloatArray) -> FloatArray | None:
    """Return the KKT-certified optimum near ``x``, or None if no nearby guess certifies.

    For each distance in :data:`ACTIVE_GUESSES`, the limits (boxes and rows, as the
    unit-norm rows of :meth:`StepProblem.inequalities`) that ``x`` meets or breaks
    within that distance are held as equalities and the rest solved exactly; the first
    candidate that meets every limit and the KKT conditions is the optimum (the QP is
    strictly convex, so it is unique).

    Parameters
    ----------
    problem : StepProblem
        The step (``x`` in [rad/s, m/s]).
    x : ndarray, shape (n,)
        Approximate answer.

    Returns
    -------
    ndarray or None
        The certified optimum, clipped into the boxes.
    """
    if not np.isfinite(x).all():
        return None
    ineq = problem.inequalities()
    C, e = ineq.C, ineq.e
    slack = np.maximum(1.0, np.abs(e))
    gap = C @ x - e
    pinned = problem.upper - problem.lower <= 1e-12 * np.maximum(1.0, np.abs(problem.lower))
    # Both sides of a pinned box are held (they are one equality). A general row's
    # index is a row of G, not a variable: only boxes are looked up.
    boxes = ineq.kind != 0
    pinned_rows = np.zeros(boxes.shape, dtype=bool)
    pinned_rows[boxes] = pinned[ineq.index[boxes]]
    tried: set[bytes] = set()
    for rel in ACTIVE_GUESSES:
        held = (gap >= -rel * slack) | pinned_rows
        key = np.packbits(held).tobytes()
        if key in tried:
            continue
        tried.add(key)
        E = np.vstack([problem.A, C[held]])
        r = np.concatenate([problem.b, e[held]])
        cand, _ = least_distance_eq(problem, E, r)
        if not np.isfinite(cand).all():
            continue
        if problem.m and float(np.abs(problem.A @ cand - problem.b).max()) > 1e-9 * max(
                1.0, float(np.abs(problem.b).max())):
            continue  # too few free directions for the task: the guess is wrong
        if ((C @ cand - e) > PRIMAL_TOL * slack).any():
            continue
        cand = np.clip(cand, problem.lower, problem.upper)
        if kkt_holds(problem, cand):
            return cand
    return None
