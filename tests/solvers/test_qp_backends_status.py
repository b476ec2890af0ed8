"""Every available qp:<backend>: honest statuses, the optimum, and warm starts that agree."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from solver_cases import random_problem, reference_qp, relative_error

from dualarm_qp.solvers import Status, available_solvers, get_solver
from dualarm_qp.solvers._kkt import refine
from dualarm_qp.step.problem import StepProblem

QP = [n for n in available_solvers() if n.startswith("qp:")]
#: Backends that may miss a feasible instance (of 40, 10 with s7 = 1e9); a miss is ERROR,
#: never OPTIMAL or INFEASIBLE. Measured on these seeds with the raw cost: osqp 7,
#: proxsuite 8, quadprog 5, clarabel 3; with the cost normalised (backends.shifted.cost_weights)
#: and the present profiles: none. The first-order backends keep a little headroom.
MAY_MISS = {"qp:osqp": 2, "qp:proxsuite": 1}


def _feasible(seed: int, count: int, s7: float | None = None
              ) -> list[tuple[StepProblem, np.ndarray]]:
    rng = np.random.default_rng(seed)
    out = []
    while len(out) < count:
        problem = random_problem(rng, cond=float(rng.choice([1.0, 10.0, 100.0])), s7=s7)
        ref = reference_qp(problem)
        if ref is not None:
            out.append((problem, ref))
    return out


def _infeasible(rng: np.random.Generator) -> list[StepProblem]:
    """Task beyond reach (scaled far out), a pinned joint, and an empty box."""
    out = []
    for _ in range(4):
        p = random_problem(rng)
        out.append(dataclasses.replace(p, b=p.b * 50.0 + 10.0))
    p = random_problem(rng)
    far = np.full(7, 1e3)
    out.append(dataclasses.replace(p, lower=p.lower + far, upper=p.upper + far))
    p = random_problem(rng)
    lower = p.lower.copy()
    lower[2] = p.upper[2] + 0.1
    out.append(dataclasses.replace(p, lower=lower))
    return out


@pytest.mark.parametrize("name", QP)
def test_infeasible_steps_are_reported_infeasible(name: str) -> None:
    solver = get_solver(name)
    for problem in _infeasible(np.random.default_rng(3)):
        sol = solver.solve(problem)
        assert sol.status is Status.INFEASIBLE, (sol.status, sol.message)
        assert np.isfinite(sol.x).all()


@pytest.mark.parametrize("name", QP)
def test_feasible_steps_match_the_reference(name: str) -> None:
    solver = get_solver(name)
    cases = _feasible(20240611, 30) + _feasible(7, 10, s7=1e9)
    missed = 0
    for problem, ref in cases:
        sol = solver.solve(problem)
        if sol.status is Status.OPTIMAL:
            assert relative_error(sol.x, ref) < 1e-6, sol.message
        else:
            assert sol.status is Status.ERROR, (sol.status, sol.message)  # never INFEASIBLE
            missed += 1
    assert missed <= MAY_MISS.get(name, 0), missed


@pytest.mark.parametrize("name", QP)
def test_warm_started_neighbours_agree_with_cold_solves(name: str) -> None:
    """A smooth sequence solved by one instance (warm) equals fresh solves (cold)."""
    base, _ = _feasible(11, 1)[0]
    rng = np.random.default_rng(5)
    warm = get_solver(name)
    x_prev = None
    drift = rng.normal(0.0, 1e-3, base.b.shape)
    for k in range(15):
        problem = dataclasses.replace(base, b=base.b + k * drift, x_prev=x_prev)
        w = warm.solve(problem)
        c = get_solver(name).solve(dataclasses.replace(problem, x_prev=None))
        assert w.status is c.status
        if c.status is Status.OPTIMAL:
            assert relative_error(w.x, c.x) < 1e-6
            x_prev = w.x
        else:
            x_prev = None


@pytest.mark.parametrize("name", QP)
def test_shape_change_is_a_fresh_setup(name: str) -> None:
    """The same instance solves a 6 x 7 then a 5 x 7 step (a new native setup)."""
    solver = get_solver(name)
    rng = np.random.default_rng(12)
    for m in (6, 5, 6):
        problem = random_problem(rng, m=m)
        sol = solver.solve(problem)
        # FEASIBLE: the backend said solved but no certificate holds (clarabel's 5 x 7
        # answer here is 6e-3 off the optimum), so it may not claim OPTIMAL.
        assert sol.status in (Status.OPTIMAL, Status.FEASIBLE, Status.ERROR), sol.message
        assert sol.bound_violation <= 1e-7 or sol.status is Status.ERROR
        if sol.status is Status.OPTIMAL:
            exact = get_solver("nullspace").solve(problem)
            assert relative_error(sol.x, exact.x) < 1e-6


def test_refine_certifies_the_optimum_from_a_rough_point() -> None:
    problem, ref = _feasible(1, 1)[0]
    rough = ref + np.random.default_rng(0).normal(0.0, 1e-8, 7)
    x = refine(problem, rough)
    assert x is not None
    assert relative_error(x, ref) < 1e-9


def test_refine_rejects_a_wrong_active_set() -> None:
    problem, ref = _feasible(2, 1)[0]
    far = 0.5 * (problem.lower + problem.upper)  # an interior point: no bound guessed
    x = refine(problem, far)
    assert x is None or relative_error(x, ref) < 1e-9
