"""The exact solver's solve and certificate in one kernel call (``solve_certified``).

A controller's ``nullspace`` step is solved and certified by one kernel call; its
answer must be the one the two calls give (``certify(problem, solver.solve(problem))``),
field by field and bit for bit, on the recorded instance suite and on random problems
with rows, infeasible and rank-deficient ones included. The call is taken for the
registry's own solver class only: a user's solver that calls itself ``nullspace`` is
certified by :func:`certify` as every other solver.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from solver_cases import random_problem, with_rows
from test_recorded_answers import CASES

from dualarm_qp.solvers import Status, StepSolution, certify, get_solver
from dualarm_qp.solvers.base import DEFAULT_TOLERANCE, Tolerance
from dualarm_qp.solvers.nullspace import NullspaceSolver
from dualarm_qp.solvers.registry import certified
from dualarm_qp.step.problem import StepProblem

#: Fields that must agree exactly (times differ).
COMPARED = [f.name for f in dataclasses.fields(StepSolution)
            if f.name not in ("solve_time", "build_time")]


def same(a: StepSolution, b: StepSolution) -> None:
    """Every compared field of ``a`` and ``b`` is equal (arrays bit for bit)."""
    for name in COMPARED:
        u, v = getattr(a, name), getattr(b, name)
        if isinstance(u, np.ndarray):
            assert u.dtype == v.dtype and np.array_equal(u, v, equal_nan=True), name
        elif isinstance(u, float) and np.isnan(u):
            assert np.isnan(v), name
        else:
            assert u == v, (name, u, v)


def fresh(problem: StepProblem) -> StepProblem:
    """``problem`` without its cache (each path computes its own basis and rows)."""
    return dataclasses.replace(problem)


def both(problem: StepProblem, tol: Tolerance = DEFAULT_TOLERANCE,
         claims_bounds: bool = True) -> tuple[StepSolution, StepSolution]:
    solver = NullspaceSolver()
    one = solver.solve_certified(fresh(problem), tol, claims_bounds)
    p = fresh(problem)
    two = certify(p, solver.solve(p), tol, claims_bounds=claims_bounds)
    return one, two


def test_recorded_instances_give_the_two_calls_answer() -> None:
    verdicts = set()
    for case in CASES:
        one, two = both(case["problem"])
        same(one, two)
        assert one.status.value == case["verdict"]
        verdicts.add(one.status)
    # The suite reaches optima and infeasible steps at least.
    assert {Status.OPTIMAL, Status.INFEASIBLE} <= verdicts


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), n=st.integers(2, 9), rows=st.integers(0, 4),
       squeeze=st.booleans(), rank_drop=st.booleans())
def test_random_steps_give_the_two_calls_answer(seed: int, n: int, rows: int,
                                                squeeze: bool, rank_drop: bool) -> None:
    rng = np.random.default_rng(seed)
    m = int(rng.integers(1, n))
    problem = random_problem(rng, n=n, m=m)
    if rows:
        problem = with_rows(problem, rng, rows)
        if squeeze:  # rows pushed past the feasible point: often infeasible
            norms = np.linalg.norm(problem.G, axis=1)
            problem = dataclasses.replace(problem, h=problem.h - rng.uniform(0, 2) * norms)
    if rank_drop and m >= 2:
        A = problem.A.copy()
        A[-1] = A[0] * (1.0 + 1e-9 * rng.standard_normal())  # near-dependent rows
        problem = dataclasses.replace(problem, A=A, b=A @ np.linalg.lstsq(
            problem.A, problem.b, rcond=None)[0])
    for claims_bounds in (True, False):
        one, two = both(problem, claims_bounds=claims_bounds)
        same(one, two)


def test_an_empty_box_gives_the_two_calls_answer() -> None:
    problem = random_problem(np.random.default_rng(3))
    lower = problem.lower.copy()
    lower[2] = problem.upper[2] + 1.0
    one, two = both(dataclasses.replace(problem, lower=lower))
    same(one, two)
    assert one.status is Status.INFEASIBLE


def test_the_registry_solver_takes_the_kernel_call(monkeypatch: pytest.MonkeyPatch) -> None:
    solver = get_solver("nullspace")
    calls = []
    original = NullspaceSolver.solve_certified

    def spy(self: NullspaceSolver, *args: object, **kwargs: object) -> StepSolution:
        calls.append(1)
        return original(self, *args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(NullspaceSolver, "solve_certified", spy)
    solver = certified(NullspaceSolver())  # built after the spy: binds it
    out = solver.solve(random_problem(np.random.default_rng(1)))
    assert calls == [1] and out.status is Status.OPTIMAL


class Impostor:
    """A user's solver that calls itself ``nullspace`` and claims a wrong optimum."""

    name = "nullspace"

    def solve(self, problem: StepProblem) -> StepSolution:
        return StepSolution(x=np.full(problem.n, 123.0), status=Status.OPTIMAL)

    def solve_certified(self, problem: StepProblem, tol: Tolerance,
                        claims_bounds: bool = True) -> StepSolution:
        raise AssertionError("a user's solver is never trusted to certify itself")


def test_a_users_solver_of_the_same_name_is_certified_by_certify() -> None:
    out = certified(Impostor()).solve(random_problem(np.random.default_rng(2)))  # type: ignore[arg-type]
    assert out.status is Status.VIOLATION


def test_the_kernel_refuses_a_cost_of_the_wrong_size() -> None:
    from dualarm_qp._compiled import kernel

    p = random_problem(np.random.default_rng(4))
    n = p.n
    empty_v, empty_m = np.zeros(0), np.zeros((0, 0))
    for w_diag, w_full, root in ((np.ones(n - 1), empty_m, empty_m),
                                 (empty_v, np.eye(n - 1), np.eye(n - 1)),
                                 (empty_v, np.eye(n), np.eye(n + 1)),
                                 (np.ones(n), np.eye(n), np.eye(n))):
        with pytest.raises(ValueError, match="the cost is"):
            kernel.solve_certified(p.A, p.b, p.lower, p.upper, p.G, p.h, w_diag, w_full,
                                   root, p.center, 1e-10, -1, True, 1e-9, 1e-7)
