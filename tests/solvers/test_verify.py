"""verify() and verified_solution(): one check, the same result, stamped with its tolerance."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from solver_cases import random_problem

from dualarm_qp.solvers import get_solver
from dualarm_qp.solvers.base import (
    DEFAULT_TOLERANCE,
    Status,
    StepSolution,
    Tolerance,
    _solution,
    residuals,
    verified_solution,
    verify,
)

FIELDS = [f.name for f in dataclasses.fields(StepSolution)]


def assert_same_solution(a: StepSolution, b: StepSolution) -> None:
    for name in FIELDS:
        va, vb = getattr(a, name), getattr(b, name)
        if isinstance(va, np.ndarray):
            assert va.dtype == vb.dtype, name
            np.testing.assert_array_equal(va, vb, err_msg=name)
        elif isinstance(va, float) and np.isnan(va):
            assert np.isnan(vb), name
        else:
            assert va == vb, name


@pytest.mark.parametrize("shift", [0.0, 1e-3, 10.0, np.nan])
@pytest.mark.parametrize("status", [Status.OPTIMAL, Status.RELAXED, Status.INFEASIBLE])
def test_verified_solution_equals_verify_of_a_solution(shift, status):
    problem = random_problem(np.random.default_rng(2))
    x = get_solver("nullspace").solve(problem).x + shift
    tol = Tolerance(equality=1e-6, bounds=1e-6)
    raw = StepSolution(x=x, status=status, solver="s", solve_time=0.5, scale=1.0,
                       message="", extras={"k": 1})
    a = verify(problem, raw, tol, claims_bounds=False)
    b = verified_solution(problem, x, status, solver="s", tol=tol, claims_bounds=False,
                          solve_time=0.5, extras={"k": 1})
    assert_same_solution(a, b)
    assert a.verified_with == tol


def test_verify_fills_what_the_dataclass_holds():
    problem = random_problem(np.random.default_rng(5))
    sol = get_solver("nullspace").solve(problem)
    assert sol.verified_with == DEFAULT_TOLERANCE
    assert StepSolution(x=sol.x, status=Status.OPTIMAL).verified_with is None
    eq, viol = residuals(problem, sol.x)
    assert sol.eq_residual == eq and sol.bound_violation == viol
    assert sol.objective == pytest.approx(float((sol.x - problem.center) @ (
        problem.weights * (sol.x - problem.center))), rel=1e-14)
    act = max(DEFAULT_TOLERANCE.bounds, 1e-9)
    np.testing.assert_array_equal(sol.active_lower, sol.x <= problem.lower + act)
    np.testing.assert_array_equal(sol.active_upper, sol.x >= problem.upper - act)
    # The fast construction gives the same object as the dataclass constructor.
    rebuilt = StepSolution(**{name: getattr(sol, name) for name in FIELDS})
    assert_same_solution(sol, rebuilt)
    assert rebuilt == sol


def test_fast_construction_needs_every_field():
    with pytest.raises(TypeError, match="objective"):
        _solution(x=np.zeros(1), status=Status.OPTIMAL)


def test_a_misshaped_x_is_an_error():
    problem = random_problem(np.random.default_rng(6))
    out = verify(problem, StepSolution(x=np.zeros(3), status=Status.OPTIMAL))
    assert out.status is Status.ERROR and out.x.shape == (7,)
    assert out.verified_with == DEFAULT_TOLERANCE
