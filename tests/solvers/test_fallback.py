"""solve_step's fallback: a feasible step that the solver fails is solved by another one."""

from __future__ import annotations

import dataclasses
import inspect

import numpy as np
import pytest
from solver_cases import lp_max_scale, random_problem

from dualarm_qp.errors import InfeasibleStepError
from dualarm_qp.solvers import Status, StepSolution, available_solvers, get_solver, solve_step
from dualarm_qp.solvers.base import failed
from dualarm_qp.solvers.nullspace import NullspaceSolver
from dualarm_qp.step.problem import StepProblem


class Failing:
    """A solver that fails every step the way it is told to, and counts its calls."""

    def __init__(self, status: Status = Status.ERROR, name: str = "fake:fail") -> None:
        self.name = name
        self.status = status
        self.calls = 0

    def solve(self, problem: StepProblem) -> StepSolution:
        self.calls += 1
        if self.status is Status.VIOLATION:  # a usable claim that breaks the bounds
            x = problem.upper + 1.0
            return StepSolution(x=x, status=Status.OPTIMAL, solver=self.name)
        return failed(problem, self.status, self.name, "deliberate failure", 1e-3)


class Counting:
    """Wraps a solver and counts its calls."""

    def __init__(self, inner: NullspaceSolver) -> None:
        self.inner = inner
        self.name = inner.name
        self.calls = 0

    def solve(self, problem: StepProblem) -> StepSolution:
        self.calls += 1
        return self.inner.solve(problem)


def feasible(seed: int) -> StepProblem:
    return random_problem(np.random.default_rng(seed))


def too_large_task(seed: int) -> StepProblem:
    """b five times a feasible one, boxes containing 0: 0 < s_max < 1."""
    p = random_problem(np.random.default_rng(seed))
    problem = dataclasses.replace(p, b=5.0 * p.b, lower=np.minimum(p.lower, -0.05),
                                  upper=np.maximum(p.upper, 0.05))
    s = lp_max_scale(problem)
    assert s is not None and 0.0 < s < 1.0
    return problem


def test_default_is_no_fallback() -> None:
    """The bench measures each solver's own success: solve_step falls back only if told."""
    assert inspect.signature(solve_step).parameters["fallback"].default is None


@pytest.mark.parametrize("status", [Status.ERROR, Status.INFEASIBLE, Status.VIOLATION])
def test_feasible_step_failed_by_the_solver_is_solved_by_the_fallback(status: Status) -> None:
    problem = feasible(1)
    exact = NullspaceSolver().solve(problem)
    primary = Failing(status)
    sol = solve_step(primary, problem, fallback=NullspaceSolver())
    assert sol.status is Status.OPTIMAL
    np.testing.assert_array_equal(sol.x, exact.x)
    assert sol.solver == "fake:fail"  # the configured solver's name stays
    record = sol.extras["fallback"]
    assert record["from"] == "fake:fail" and record["to"] == "nullspace"
    assert record["status"] == status.value
    assert record["message"]
    assert sol.message.startswith(f"fake:fail {status.value} (")
    assert "solved by nullspace" in sol.message
    assert sol.solve_time >= 1e-3 or status is Status.VIOLATION  # both solves counted
    assert sol.bound_violation <= 1e-7 and sol.verified_with is not None


def test_without_fallback_the_failure_is_returned() -> None:
    problem = feasible(2)
    sol = solve_step(Failing(), problem)
    assert sol.status is Status.ERROR
    assert "fallback" not in sol.extras
    assert sol.message == "deliberate failure"


def test_usable_answer_never_calls_the_fallback() -> None:
    fallback = Counting(NullspaceSolver())
    for seed in range(5):
        sol = solve_step(NullspaceSolver(), feasible(seed), fallback=fallback)
        assert sol.status is Status.OPTIMAL and "fallback" not in sol.extras
    assert fallback.calls == 0


def test_fallback_that_fails_too_is_reported() -> None:
    problem = feasible(3)
    sol = solve_step(Failing(name="first"), problem,
                     fallback=Failing(Status.ERROR, name="second"))
    assert sol.status is Status.ERROR
    assert sol.extras["fallback"]["from"] == "first"
    assert sol.extras["fallback"]["to"] == "second"
    assert "second failed too" in sol.message
    assert np.isfinite(sol.x).all()


def test_scale_policy_uses_the_fallback_for_the_scaled_solve() -> None:
    """Infeasible step: the scaled inner solve fails, the fallback solves it (SCALED)."""
    problem = too_large_task(0)
    reference = solve_step(NullspaceSolver(), problem, "scale")
    assert reference.status is Status.SCALED
    sol = solve_step(Failing(), problem, "scale", fallback=NullspaceSolver())
    assert sol.status is Status.SCALED
    assert sol.solver == "fake:fail"
    assert sol.scale == pytest.approx(reference.scale, rel=1e-12)
    np.testing.assert_allclose(sol.x, reference.x, atol=1e-12)
    assert "point" not in sol.extras  # not the feasibility point
    assert sol.extras["fallback"] == {"from": "fake:fail", "to": "nullspace",
                                      "status": "error", "message": "deliberate failure"}
    assert sol.extras["inner_status"] is Status.ERROR
    assert "solved by nullspace" in sol.message


def test_scale_policy_without_fallback_keeps_the_feasibility_point() -> None:
    problem = too_large_task(1)
    sol = solve_step(Failing(), problem, "scale")
    assert sol.status is Status.SCALED
    assert sol.extras.get("point") == "feasibility"
    assert "fallback" not in sol.extras


def test_relax_and_stop_on_infeasible_steps_do_not_fall_back() -> None:
    problem = too_large_task(2)
    fallback = Counting(NullspaceSolver())
    sol = solve_step(Failing(), problem, "relax", fallback=fallback)
    assert sol.status is Status.RELAXED and "fallback" not in sol.extras
    with pytest.raises(InfeasibleStepError):
        solve_step(Failing(), problem, "stop", fallback=fallback)
    assert fallback.calls == 0


@pytest.mark.parametrize("policy", ["scale", "relax", "stop"])
def test_feasible_step_falls_back_under_every_policy(policy: str) -> None:
    problem = feasible(4)
    sol = solve_step(Failing(), problem, policy, fallback=NullspaceSolver())  # type: ignore[arg-type]
    assert sol.status is Status.OPTIMAL and "fallback" in sol.extras


# Real backends held to one iteration: they fail most clearly feasible steps.
CRIPPLED = {"qp:osqp": {"max_iter": 1, "polishing": False},
            "qp:proxsuite": {"max_iter": 1, "max_iter_in": 1}}


@pytest.mark.parametrize("name", sorted(CRIPPLED))
def test_real_backend_failures_are_solved_by_the_fallback(name: str) -> None:
    if name not in available_solvers():
        pytest.skip(f"{name} is not installed")
    primary = get_solver(name, **CRIPPLED[name])
    exact = NullspaceSolver()
    failures = 0
    for seed in range(20):
        problem = feasible(100 + seed)
        alone = primary.solve(problem)
        sol = solve_step(primary, problem, fallback=exact)
        assert sol.status is Status.OPTIMAL, sol.message
        assert sol.solver == name
        if alone.status.usable:
            continue
        failures += 1
        assert sol.extras["fallback"]["from"] == name
        assert sol.extras["fallback"]["status"] == alone.status.value
        np.testing.assert_allclose(sol.x, exact.solve(problem).x, atol=1e-9)
    assert failures >= 5  # the test exercises the fallback
