"""Random degenerate steps with a known feasible task scale, and HiGHS's largest scale.

The steps have the shape of the project's one-vector step (12 equality rows, both arms'
six joints and one or two grasp columns) and every degeneracy the task-scale LP meets in
real steps at once: ``x = 0`` outside the box (a joint braking under its acceleration
limit), pinned variables (``lower == upper``), equality rows that are dependent (an arm
at a singularity), families of nearly parallel general rows, and a single feasible scale
(two opposite rows). A point ``x*`` meets every row exactly at the scale ``s_true``: every
row through it is tight there, so the optimum sits at a degenerate vertex.

Nearly parallel rows differ by ``1e-14`` to ``1e-10`` (duplicates up to rounding) or by
``1e-6`` to ``1e-3`` (distinct). Rows that differ by about the feasibility tolerance
(``1e-10`` to ``1e-7``) make the largest scale itself ill-posed: a violation of ``1e-9``
buys up to a tenth of the scale there, for any solver, so no solver can be held to
another's answer on them (measured: HiGHS and the kernel then differ by up to 0.13, each
with its point within 1e-9 of every row).

``highs_scale`` solves the same LP directly in ``x`` with SciPy's HiGHS: an independent
answer, sharing nothing with the library's reduction to the null space.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linprog

from dualarm_qp.step.problem import StepProblem

#: The two ranges (decades) of the difference between nearly parallel rows.
DUPLICATES = (-14.0, -10.0)
DISTINCT = (-6.0, -3.0)


def degenerate_step(rng: np.random.Generator) -> tuple[StepProblem, float]:
    """A degenerate step and a task scale that is feasible by construction.

    Returns
    -------
    problem : StepProblem
        ``A`` (12 x 13 or 12 x 14), ``b = A x* / s_true``, boxes, general rows.
    s_true : float
        A feasible scale (the largest may be larger, unless the step has a single one).
    """
    n_grasp = int(rng.integers(1, 3))
    n, m = 12 + n_grasp, 12
    A = rng.normal(size=(m, n)) * np.r_[rng.uniform(0.1, 1.0, 12), rng.uniform(0.5, 2.0, n_grasp)]
    if rng.random() < 0.4:  # dependent equality rows
        k = int(rng.integers(1, 3))
        A[m - k:] = rng.normal(size=(k, m - k)) @ A[:m - k]
    x_star = rng.uniform(-1.0, 1.0, n)
    lower = x_star - rng.uniform(0.05, 1.0, n)
    upper = x_star + rng.uniform(0.05, 1.0, n)
    j = int(np.argmax(np.abs(x_star)))  # braking: x = 0 is outside this box
    if x_star[j] > 0.0:
        lower[j] = 0.5 * x_star[j]
    else:
        upper[j] = 0.5 * x_star[j]
    pinned = rng.choice(n, size=int(rng.integers(1, 4)), replace=False)
    lower[pinned] = upper[pinned] = x_star[pinned]
    rows = []
    for _ in range(int(rng.integers(1, 4))):  # a family of nearly parallel rows
        g = rng.normal(size=n) if rng.random() < 0.5 else np.eye(n)[rng.integers(n)]
        for _ in range(int(rng.integers(2, 4))):
            decades = DUPLICATES if rng.random() < 0.5 else DISTINCT
            rows.append(g + rng.normal(size=n) * 10.0 ** rng.uniform(*decades))
    if rng.random() < 0.5:  # g x = g x*: a single feasible scale
        g = rng.normal(size=n)
        rows += [g, -g]
    G = np.array(rows)
    s_true = 1.0 if rng.random() < 0.25 else float(rng.uniform(0.05, 0.95))
    problem = StepProblem(A, A @ x_star / s_true, np.ones(n), np.zeros(n), lower, upper,
                          G=G, h=G @ x_star, n_grasp=n_grasp)
    return problem, s_true


def highs_scale(problem: StepProblem) -> float | None:
    """Largest ``s`` in ``[0, 1]`` with ``A x = s b``, the box and ``G x <= h``, by HiGHS.

    None when HiGHS reports no optimum.
    """
    n = problem.n
    cost = np.zeros(n + 1)
    cost[n] = -1.0
    bounds = [(lo if np.isfinite(lo) else None, up if np.isfinite(up) else None)
              for lo, up in zip(problem.lower, problem.upper, strict=True)] + [(0.0, 1.0)]
    rows = {}
    if problem.p:
        rows = {"A_ub": np.hstack([problem.G, np.zeros((problem.p, 1))]), "b_ub": problem.h}
    res = linprog(cost, A_eq=np.hstack([problem.A, -problem.b[:, None]]),
                  b_eq=np.zeros(problem.m), bounds=bounds, method="highs", **rows)
    return float(res.x[n]) if res.status == 0 else None
