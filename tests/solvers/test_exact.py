"""The exact solvers against independent references: KKT systems and active-set enumeration."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from solver_cases import kkt_equality, random_problem, reference_qp, relative_error

from dualarm_qp.solvers import Status, get_solver
from dualarm_qp.step.problem import StepProblem

seeds = st.integers(min_value=0, max_value=2**32 - 1)


@settings(max_examples=60, deadline=None)
@given(seed=seeds, cond=st.sampled_from([1.0, 10.0, 100.0]))
def test_reference_is_the_equality_constrained_minimiser(seed: int, cond: float) -> None:
    """Eq. 29 with the z-hat formula equals the KKT solution of min ||x-c||_S^2, A x = b."""
    problem = random_problem(np.random.default_rng(seed), cond=cond)
    sol = get_solver("reference").solve(problem)
    assert relative_error(sol.x, kkt_equality(problem)) < 1e-8
    inside = bool(((sol.x >= problem.lower - 1e-7) & (sol.x <= problem.upper + 1e-7)).all())
    assert sol.status is (Status.OPTIMAL if inside else Status.VIOLATION)


@settings(max_examples=150, deadline=None)
@given(seed=seeds, cond=st.sampled_from([1.0, 10.0, 100.0]),
       s7=st.sampled_from([1e2, 1e4, 1e6]))
def test_nullspace_is_exact_on_6x7(seed: int, cond: float, s7: float) -> None:
    """The scalar clamp equals the enumerated optimum to 1e-9 (relative)."""
    problem = random_problem(np.random.default_rng(seed), cond=cond, s7=s7)
    ref = reference_qp(problem)
    assert ref is not None
    sol = get_solver("nullspace").solve(problem)
    assert sol.status is Status.OPTIMAL, sol.message
    assert relative_error(sol.x, ref) < 1e-9


@settings(max_examples=40, deadline=None)
@given(seed=seeds, cond=st.sampled_from([1.0, 100.0]))
def test_nullspace_active_set_is_exact_on_6x8(seed: int, cond: float) -> None:
    """Two redundant variables (two grasp speeds): the active-set method is exact."""
    problem = random_problem(np.random.default_rng(seed), n=8, cond=cond, n_grasp=2)
    ref = reference_qp(problem)
    if ref is None:  # a degenerate optimum with more than n - m active bounds
        return
    sol = get_solver("nullspace").solve(problem)
    assert sol.status is Status.OPTIMAL, sol.message
    assert relative_error(sol.x, ref) < 1e-9


def test_nullspace_square_system() -> None:
    """No redundancy (6 x 6): the unique solution, or INFEASIBLE if it leaves the box."""
    problem = random_problem(np.random.default_rng(1), n=6, n_grasp=0)
    sol = get_solver("nullspace").solve(problem)
    assert sol.status is Status.OPTIMAL
    assert sol.extras["nullity"] == 0
    assert relative_error(sol.x, np.linalg.solve(problem.A, problem.b)) < 1e-10
    far = StepProblem(A=problem.A, b=10.0 * problem.b, weights=problem.weights,
                      center=problem.center, lower=problem.lower, upper=problem.upper,
                      n_grasp=0)
    assert get_solver("nullspace").solve(far).status is Status.INFEASIBLE


def test_nullspace_survives_a_singular_joint_block() -> None:
    """A[:, :6] numerically singular (arm singularity): the SVD gives the exact answer."""
    rng = np.random.default_rng(5)
    base = random_problem(rng)
    A = base.A.copy()
    A[:, 5] = A[:, 4] * 2.0 + 1e-13 * rng.standard_normal(6)  # joint block rank 5
    x_f = np.clip(np.zeros(7), base.lower, base.upper)
    problem = StepProblem(A=A, b=A @ x_f, weights=base.weights, center=base.center,
                          lower=np.full(7, -5.0), upper=np.full(7, 5.0))
    ref = reference_qp(problem)
    assert ref is not None
    sol = get_solver("nullspace").solve(problem)
    assert sol.status is Status.OPTIMAL, sol.message
    assert relative_error(sol.x, ref) < 1e-7


def test_nullspace_reports_the_conflicting_bounds() -> None:
    """An empty t-interval names the two bounds that cross."""
    problem = random_problem(np.random.default_rng(2))
    tight = StepProblem(A=problem.A, b=5.0 * problem.b + 3.0, weights=problem.weights,
                        center=problem.center, lower=problem.lower, upper=problem.upper)
    sol = get_solver("nullspace").solve(tight)
    assert sol.status is Status.INFEASIBLE
    conflicts = sol.extras["conflicts"]
    assert 1 <= len(conflicts) <= 2
    assert all(name.split()[0] in problem.names for name in conflicts)
    assert all(name in sol.message for name in conflicts)
    assert not np.isnan(sol.x).any()


def test_fixed_grasp_holds_the_grasp() -> None:
    """Sliding speed zero and the 6 x 6 joint system solved exactly."""
    problem = random_problem(np.random.default_rng(3))
    sol = get_solver("fixed_grasp").solve(problem)
    assert sol.x[6] == 0.0
    assert np.allclose(problem.A[:, :6] @ sol.x[:6], problem.b, atol=1e-10)
    assert sol.eq_residual < 1e-9


def test_fixed_grasp_non_square_is_the_weighted_least_distance() -> None:
    """6 x 8 with one grasp speed: the KKT minimiser over the 7 remaining variables."""
    problem = random_problem(np.random.default_rng(4), n=8, n_grasp=1)
    sol = get_solver("fixed_grasp").solve(problem)
    reduced = StepProblem(A=problem.A[:, :7], b=problem.b, weights=problem.weights[:7],
                          center=problem.center[:7], lower=problem.lower[:7],
                          upper=problem.upper[:7])
    assert sol.x[7] == 0.0
    assert relative_error(sol.x[:7], kkt_equality(reduced)) < 1e-9


@pytest.mark.parametrize("name", ["nullspace", "sns", "qp:daqp"])
def test_empty_box_is_infeasible_with_names(name: str) -> None:
    """lower > upper on a variable: INFEASIBLE, the variable named, no NaN."""
    from dualarm_qp.solvers import available_solvers

    if name not in available_solvers():
        pytest.skip(f"{name} not installed")
    problem = random_problem(np.random.default_rng(6))
    lower = problem.lower.copy()
    lower[2] = problem.upper[2] + 0.1
    bad = StepProblem(A=problem.A, b=problem.b, weights=problem.weights,
                      center=problem.center, lower=lower, upper=problem.upper)
    sol = get_solver(name).solve(bad)
    assert sol.status is Status.INFEASIBLE
    assert sol.extras["conflicts"] == (problem.names[2],)
    assert np.isfinite(sol.x).all()


def test_nullspace_rank_deficient_equality() -> None:
    """A repeated row (rank 5): consistent b is solved exactly, inconsistent b is INFEASIBLE."""
    p = random_problem(np.random.default_rng(14))
    A = np.vstack([p.A[:5], p.A[4]])
    x_f = 0.5 * (p.lower + p.upper)
    problem = StepProblem(A=A, b=A @ x_f, weights=p.weights, center=p.center,
                          lower=p.lower, upper=p.upper)
    reduced = StepProblem(A=A[:5], b=problem.b[:5], weights=p.weights, center=p.center,
                          lower=p.lower, upper=p.upper)
    ref = reference_qp(reduced)
    assert ref is not None
    sol = get_solver("nullspace").solve(problem)
    assert sol.status is Status.OPTIMAL, sol.message
    assert sol.extras["nullity"] == 2  # rank 5, decided by the SVD (not an LU pivot)
    assert relative_error(sol.x, ref) < 1e-9
    b_bad = problem.b.copy()
    b_bad[5] += 1.0
    bad = StepProblem(A=A, b=b_bad, weights=p.weights, center=p.center, lower=p.lower,
                      upper=p.upper)
    assert get_solver("nullspace").solve(bad).status is Status.INFEASIBLE
