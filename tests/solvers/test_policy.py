"""Infeasible steps under each policy, for every available solver: documented status,
no NaN, no exception except the one ``stop`` promises."""

from __future__ import annotations

import numpy as np
import pytest
from solver_cases import lp_max_scale, random_problem

from dualarm_qp.errors import InfeasibleStepError, InvalidInputError
from dualarm_qp.solvers import Status, available_solvers, get_solver, solve_step
from dualarm_qp.step.problem import StepProblem

SOLVERS = available_solvers()


def too_large_task(seed: int) -> StepProblem:
    """b five times a feasible one, boxes containing 0: 0 < s_max < 1."""
    p = random_problem(np.random.default_rng(seed))
    problem = StepProblem(A=p.A, b=5.0 * p.b, weights=p.weights, center=p.center,
                          lower=np.minimum(p.lower, -0.05), upper=np.maximum(p.upper, 0.05))
    s = lp_max_scale(problem)
    assert s is not None and 0.0 < s < 1.0
    return problem


def nowhere_feasible() -> StepProblem:
    """Every box pinched at a point v with A v not parallel to b: no s works, not even 0."""
    p = random_problem(np.random.default_rng(11))
    v = np.linspace(0.2, 0.8, 7)
    problem = StepProblem(A=p.A, b=p.b, weights=p.weights, center=p.center, lower=v, upper=v)
    assert lp_max_scale(problem) is None
    return problem


def empty_box() -> StepProblem:
    """Variable x4 has lower > upper."""
    p = random_problem(np.random.default_rng(12))
    lower = p.lower.copy()
    lower[3] = p.upper[3] + 0.2
    return StepProblem(A=p.A, b=p.b, weights=p.weights, center=p.center, lower=lower,
                       upper=p.upper)


@pytest.mark.parametrize("name", SOLVERS)
def test_scale_reaches_the_largest_feasible_scale(name: str) -> None:
    """SCALED with s = the LP's largest feasible scale; bounds and A x = s b hold."""
    solver = get_solver(name)
    for seed in range(3):
        problem = too_large_task(seed)
        sol = solve_step(solver, problem, "scale")
        assert np.isfinite(sol.x).all()
        if name in ("reference", "fixed_grasp") and sol.status is Status.VIOLATION:
            continue  # methods without bounds: the failure is reported, not hidden
        assert sol.status is Status.SCALED, (sol.status, sol.message)
        expected = lp_max_scale(problem)
        assert expected is not None
        assert abs(sol.scale - expected) <= 1e-7 * max(1.0, expected)
        assert sol.bound_violation <= 1e-7
        assert sol.eq_residual <= 1e-7 * max(1.0, float(np.abs(problem.b).max()))


@pytest.mark.parametrize("name", SOLVERS)
def test_relax_keeps_the_bounds(name: str) -> None:
    """RELAXED: bounds hold, the task residual is what bounded least squares leaves."""
    problem = too_large_task(0)
    sol = solve_step(get_solver(name), problem, "relax")
    if sol.status is not Status.RELAXED:  # methods without bounds report VIOLATION
        assert name in ("reference", "fixed_grasp"), sol.status
        return
    assert sol.bound_violation <= 1e-9
    assert sol.eq_residual > 1e-3
    assert sol.extras["policy"] == "relax"


@pytest.mark.parametrize("name", SOLVERS)
def test_stop_raises_with_conflicts(name: str) -> None:
    """InfeasibleStepError naming existing bounds, for both kinds of infeasibility."""
    solver = get_solver(name)
    for problem in (too_large_task(1), nowhere_feasible()):
        sol = solver.solve(problem)
        if sol.status.usable:
            pytest.fail(f"{name} claimed {sol.status} on an infeasible step")
        if name in ("reference", "fixed_grasp"):
            continue
        with pytest.raises(InfeasibleStepError) as info:
            solve_step(solver, problem, "stop")
        assert info.value.conflicts
        assert all(c.split()[0] in problem.names for c in info.value.conflicts)


@pytest.mark.parametrize("name", SOLVERS)
def test_nowhere_feasible_scale_falls_back_to_relax(name: str) -> None:
    """Not even s = 0 is feasible: "scale" relaxes; the pinned boxes hold."""
    problem = nowhere_feasible()
    sol = solve_step(get_solver(name), problem, "scale")
    assert np.isfinite(sol.x).all()
    if name in ("reference", "fixed_grasp") and sol.status is Status.VIOLATION:
        return
    assert sol.status is Status.RELAXED, (sol.status, sol.message)
    assert np.allclose(sol.x, problem.lower)


@pytest.mark.parametrize("name", SOLVERS)
@pytest.mark.parametrize("policy", ["scale", "relax", "stop"])
def test_empty_box_under_each_policy(name: str, policy: str) -> None:
    """An empty box: INFEASIBLE naming it (scale, relax) or InfeasibleStepError (stop)."""
    problem = empty_box()
    solver = get_solver(name)
    if name in ("reference", "fixed_grasp"):
        sol = solve_step(solver, problem, "scale")  # never usable: the box is empty
        assert not sol.status.usable
        return
    if policy == "stop":
        with pytest.raises(InfeasibleStepError) as info:
            solve_step(solver, problem, "stop")
        assert info.value.conflicts == ("x4",)
        return
    sol = solve_step(solver, problem, policy)  # type: ignore[arg-type]
    assert sol.status is Status.INFEASIBLE
    assert sol.extras["conflicts"] == ("x4",)
    assert np.isfinite(sol.x).all()


def test_feasible_step_is_left_alone() -> None:
    """A usable answer passes through every policy unchanged."""
    problem = random_problem(np.random.default_rng(13))
    solver = get_solver("nullspace")
    direct = solver.solve(problem)
    for policy in ("scale", "relax", "stop"):
        sol = solve_step(solver, problem, policy)  # type: ignore[arg-type]
        assert sol.status is Status.OPTIMAL
        assert np.array_equal(sol.x, direct.x)


def test_unknown_policy_is_rejected() -> None:
    with pytest.raises(InvalidInputError, match="scale, relax, stop"):
        solve_step(get_solver("nullspace"), random_problem(np.random.default_rng(0)),
                   "retry")  # type: ignore[arg-type]
