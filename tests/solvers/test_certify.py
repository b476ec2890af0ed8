"""certify(): the one check of every answer, with one feasibility tolerance and one KKT test."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from solver_cases import random_problem, reference_qp

from dualarm_qp.solvers import get_solver
from dualarm_qp.solvers.base import DEFAULT_TOLERANCE, Status, StepSolution, Tolerance
from dualarm_qp.solvers.certify import certify, kkt_holds, residuals


def test_certify_fills_the_residuals_and_the_active_limits() -> None:
    problem = random_problem(np.random.default_rng(5))
    sol = get_solver("nullspace").solve(problem)
    assert sol.verified_with == DEFAULT_TOLERANCE
    assert StepSolution(x=sol.x, status=Status.OPTIMAL).verified_with is None
    eq, viol = residuals(problem, sol.x)
    assert sol.eq_residual == eq and sol.bound_violation == viol
    assert sol.objective == pytest.approx(float((sol.x - problem.center) @ (
        problem.weights * (sol.x - problem.center))), rel=1e-14)
    np.testing.assert_array_equal(sol.active_lower, sol.x <= problem.lower + 1e-9)
    np.testing.assert_array_equal(sol.active_upper, sol.x >= problem.upper - 1e-9)


def test_a_misshaped_or_non_finite_x_is_an_error() -> None:
    problem = random_problem(np.random.default_rng(6))
    for x in (np.zeros(3), np.full(7, np.nan)):
        out = certify(problem, StepSolution(x=x, status=Status.OPTIMAL))
        assert out.status is Status.ERROR and out.x.shape == (7,)
        assert np.array_equal(out.x, np.zeros(7))
        assert out.verified_with == DEFAULT_TOLERANCE


@pytest.mark.parametrize("seed", range(8))
def test_an_optimal_claim_off_the_optimum_is_feasible_never_optimal(seed: int) -> None:
    """A feasible point that is not the minimiser passes the bounds but not the KKT test."""
    problem = random_problem(np.random.default_rng(seed))
    best = reference_qp(problem)
    assert best is not None
    N = np.linalg.svd(problem.A)[2][problem.m:].T
    for step in (1e-3, 1e-5):
        moved = best + step * N[:, 0]
        if (moved < problem.lower).any() or (moved > problem.upper).any():
            moved = best - step * N[:, 0]
        if (moved < problem.lower).any() or (moved > problem.upper).any():
            continue
        out = certify(problem, StepSolution(x=moved, status=Status.OPTIMAL))
        assert out.status is Status.FEASIBLE, (seed, step)
    assert certify(problem, StepSolution(x=best, status=Status.OPTIMAL)).status \
        is Status.OPTIMAL


def test_a_scaled_answer_is_judged_against_its_scaled_right_hand_side() -> None:
    """A residual of 3e-6 passes at ``b`` (|b| ~ 100: 1e-7 of it is 1e-5) and fails at
    ``1e-4 b`` (tolerance 1e-7): the scaled task is what the answer was asked for."""
    problem = random_problem(np.random.default_rng(3))
    problem = dataclasses.replace(problem, b=100.0 * problem.b / np.abs(problem.b).max())
    tol = Tolerance(equality=1e-7, bounds=1e9)
    push = 3e-6 * np.linalg.pinv(problem.A) @ np.ones(problem.m)  # A push = 3e-6 (1, ..)
    for scale, want in ((1.0, Status.SCALED), (1e-4, Status.VIOLATION)):
        scaled = problem.scaled(scale)
        x = np.linalg.pinv(scaled.A) @ scaled.b + push
        assert certify(scaled, StepSolution(x=x, status=Status.SCALED), tol).status is want


def test_rows_are_checked_like_boxes() -> None:
    problem = random_problem(np.random.default_rng(4))
    sol = get_solver("nullspace").solve(problem)
    # A row through the answer: x_0 <= x*_0 - 1e-3, broken by the answer by 1e-3 (unit
    # normal); scaled rows are normalised before the tolerance is applied.
    G = np.zeros((1, problem.n))
    G[0, 0] = 5.0
    walled = dataclasses.replace(problem, G=G, h=np.array([5.0 * (sol.x[0] - 1e-3)]),
                                 row_names=("wall",))
    out = certify(walled, StepSolution(x=sol.x, status=Status.OPTIMAL))
    assert out.status is Status.VIOLATION and "wall" in out.message
    assert out.row_violation == pytest.approx(1e-3, rel=1e-9)
    loose = dataclasses.replace(walled, h=np.array([5.0 * (sol.x[0] + 1e-3)]))
    assert certify(loose, StepSolution(x=sol.x, status=Status.OPTIMAL)).status \
        is Status.OPTIMAL


def test_the_reference_step_is_optimal_only_over_its_equality() -> None:
    problem = random_problem(np.random.default_rng(8))
    x = get_solver("reference").solve(problem).x
    assert kkt_holds(problem, x, bounds=False)
    N = np.linalg.svd(problem.A)[2][problem.m:].T
    assert not kkt_holds(problem, x + 1e-4 * N[:, 0], bounds=False)


def test_certify_carries_every_field_it_does_not_decide() -> None:
    # certify builds its answer field by field: a field of StepSolution it neither
    # decides nor carries from the claim would silently fall back to its default.
    problem = random_problem(np.random.default_rng(11))
    x = get_solver("nullspace").solve(problem).x
    claim = StepSolution(x=x, status=Status.OPTIMAL, scale=0.5, solver="mine",
                         message="a claim", extras={"k": 1}, solve_time=2.0)
    out = certify(problem, claim)
    decided = {"x", "status", "objective", "eq_residual", "bound_violation", "active_lower",
               "active_upper", "solve_time", "build_time", "message", "verified_with",
               "row_violation", "active_rows"}
    carried = {f.name for f in dataclasses.fields(StepSolution)} - decided
    assert carried == {"scale", "solver", "extras"}
    for name in carried:
        assert getattr(out, name) == getattr(claim, name)
    assert out.message == "a claim" and out.solve_time >= 2.0


def test_the_active_rows_are_named_each_once_in_their_order() -> None:
    """Rows that bind at the answer are named by their row of ``G`` (two rows of one
    limit once), by the kernel's certified solve and by certify() of a claim alike;
    rows that do not bind, and the boxes, are not named."""
    from dualarm_qp.step.problem import StepProblem

    n = 4
    A = np.array([[1.0, 1.0, 1.0, 1.0]])
    # Minimise |x - c|^2 on sum(x) = 1 with c = (1, 1, 0, 0): the rows x0 <= 0.2 and
    # x1 <= 0.3 bind, x2 <= 5 does not; a box binds (x3 <= 0.1) but is not a row.
    G = np.array([[1.0, 0, 0, 0], [0, 1.0, 0, 0], [0, 0, 1.0, 0]])
    problem = StepProblem(
        A=A, b=np.array([1.0]), weights=np.ones(n), center=np.array([1.0, 1.0, 0.0, 0.0]),
        lower=np.full(n, -10.0), upper=np.array([10.0, 10.0, 10.0, 0.1]), G=G,
        h=np.array([0.2, 0.3, 5.0]), n_grasp=0, row_names=("wall", "wall", "far"))
    solved = get_solver("nullspace").solve(problem)
    assert solved.status is Status.OPTIMAL
    np.testing.assert_allclose(solved.x, [0.2, 0.3, 0.4, 0.1], atol=1e-12)
    assert solved.active_rows == ("wall",)
    claimed = certify(problem, StepSolution(x=solved.x, status=Status.OPTIMAL))
    assert claimed.status is Status.OPTIMAL and claimed.active_rows == ("wall",)
    free = dataclasses.replace(problem, h=np.array([5.0, 5.0, 5.0]),
                               upper=np.full(n, 10.0))
    assert get_solver("nullspace").solve(free).active_rows == ()
