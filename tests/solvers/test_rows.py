"""General rows ``G x <= h`` in the exact solver and the QP backends, against an
independent active-set enumeration (hypothesis)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from solver_cases import random_problem, reference_qp_rows, relative_error, with_rows

from dualarm_qp.solvers import Status, get_solver, list_solvers, solve_step
from dualarm_qp.solvers.certify import kkt_holds

ROW_SOLVERS = [i.name for i in list_solvers() if i.available and i.takes_rows
               and i.hard_bounds]
seeds = st.integers(min_value=0, max_value=2**32 - 1)


@pytest.mark.slow
@settings(max_examples=40, deadline=None)
@given(seed=seeds, n=st.sampled_from([7, 8, 9]), rows=st.integers(1, 4))
def test_the_exact_solver_with_rows_matches_the_enumeration(seed: int, n: int,
                                                             rows: int) -> None:
    rng = np.random.default_rng(seed)
    problem = with_rows(random_problem(rng, n=n, n_grasp=n - 6, cond=30.0), rng, rows)
    truth = reference_qp_rows(problem)
    sol = get_solver("nullspace").solve(problem)
    if truth is None:  # a degenerate instance the enumeration cannot decide: skip it
        return
    assert sol.status is Status.OPTIMAL, sol.message
    assert relative_error(sol.x, truth) <= 1e-7
    assert problem.objective(sol.x) <= problem.objective(truth) * (1 + 1e-9) + 1e-12
    assert kkt_holds(problem, sol.x)


@pytest.mark.parametrize("solver", ROW_SOLVERS)
@pytest.mark.parametrize("seed", range(6))
def test_every_solver_that_takes_rows_keeps_them(solver: str, seed: int) -> None:
    rng = np.random.default_rng(1000 + seed)
    problem = with_rows(random_problem(rng, n=8, n_grasp=2, cond=30.0), rng, 3)
    truth = reference_qp_rows(problem)
    sol = solve_step(get_solver(solver), problem, "scale")
    assert sol.status.usable, (solver, sol.status, sol.message)
    assert sol.row_violation <= 1e-7 and sol.bound_violation <= 1e-7
    if sol.status is Status.OPTIMAL and truth is not None:
        assert relative_error(sol.x, truth) <= 1e-6


@settings(max_examples=30, deadline=None)
@given(seed=seeds, rows=st.integers(1, 3), factor=st.floats(1.5, 20.0))
def test_the_task_scale_counts_the_rows(seed: int, rows: int, factor: float) -> None:
    """A task made too large by ``factor``: the scale policy's scale is the largest s at
    which A x = s b meets the boxes and the rows (HiGHS with the rows, independently)."""
    from scipy.optimize import linprog

    rng = np.random.default_rng(seed)
    base = with_rows(random_problem(rng, n=8, n_grasp=2, cond=30.0), rng, rows)
    problem = base.scaled(factor)
    n = problem.n
    cost = np.zeros(n + 1)
    cost[n] = -1.0
    res = linprog(cost, A_ub=np.hstack([problem.G, np.zeros((rows, 1))]), b_ub=problem.h,
                  A_eq=np.hstack([problem.A, -problem.b[:, None]]), b_eq=np.zeros(6),
                  bounds=[*zip(problem.lower, problem.upper, strict=True), (0.0, 1.0)],
                  method="highs")
    sol = solve_step(get_solver("nullspace"), problem, "scale")
    if res.status != 0:
        assert sol.status is not Status.SCALED
        return
    s = float(res.x[n])
    if s >= 1.0 - 1e-9:
        assert sol.status is Status.OPTIMAL
    else:
        assert sol.status is Status.SCALED, sol.message
        assert sol.scale == pytest.approx(s, abs=1e-7)
        assert sol.row_violation <= 1e-7
