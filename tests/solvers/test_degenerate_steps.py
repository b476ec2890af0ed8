"""Recorded degenerate steps on which the solvers used to go wrong, with their truth.

The four problems (``data/degenerate_steps``, README there) came from a stress campaign
of 12,000 random PUMA steps and 800 each on the Panda pair and the both-sliding bar,
each verdict checked by an independent oracle. The truths below are checked here with
independent tools (SciPy's HiGHS linear programs and an active-set enumeration), not
with the library's own code.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import linprog

from dualarm_qp.solvers import Status, available_solvers, get_solver, solve_step
from dualarm_qp.solvers._scale import max_task_scale
from dualarm_qp.solvers.certify import kkt_holds
from dualarm_qp.step.problem import StepProblem

DATA = Path(__file__).resolve().parent / "data" / "degenerate_steps"


def load(name: str) -> StepProblem:
    z = np.load(DATA / f"{name}.npz")
    return StepProblem(z["A"], z["b"], z["weights"], z["center"], z["lower"], z["upper"],
                       n_grasp=int(z["n_grasp"]))


def highs_scale(problem: StepProblem) -> float | None:
    """Largest s in [0, 1] with A x = s b inside the box, by HiGHS (independent)."""
    n = problem.n
    cost = np.zeros(n + 1)
    cost[n] = -1.0
    A_eq = np.hstack([problem.A, -problem.b[:, None]])
    bounds = [(lo if np.isfinite(lo) else None, up if np.isfinite(up) else None)
              for lo, up in zip(problem.lower, problem.upper, strict=True)] + [(0.0, 1.0)]
    res = linprog(cost, A_eq=A_eq, b_eq=np.zeros(problem.m), bounds=bounds, method="highs",
                  options={"primal_feasibility_tolerance": 1e-10})
    return None if res.status != 0 else float(res.x[n])


def test_panda_step_zero_is_solved_exactly_by_the_exact_solver() -> None:
    """nullspace used to stop with "active set did not converge in 200 iterations" (and
    the Panda run failed at step 0): the step is feasible at full scale, at a vertex."""
    problem = load("panda_nullspace_maxiter")
    sol = get_solver("nullspace").solve(problem)
    assert sol.status is Status.OPTIMAL, sol.message
    assert sol.eq_residual <= 1e-9 * max(1.0, np.abs(problem.b).max())
    assert sol.bound_violation <= 1e-9
    assert kkt_holds(problem, sol.x)
    # An independent QP solver at its tightest finds nothing lower.
    if "qp:highs" in available_solvers():
        other = get_solver("qp:highs").solve(problem)
        if other.status.usable:
            assert sol.objective <= other.objective * (1 + 1e-9) + 1e-12


def test_a_positive_task_scale_is_found_where_it_exists() -> None:
    """The scale policy used to return s = 0; s = 0.415 is feasible (HiGHS: A x = s b to
    4e-14 with no bound broken)."""
    problem = load("degenerate_scale")
    truth = highs_scale(problem)
    assert truth is not None and truth > 0.4
    reach = max_task_scale(problem)
    assert reach.scale is not None
    assert reach.scale == pytest.approx(truth, abs=1e-7)
    sol = solve_step(get_solver("nullspace"), problem, "scale")
    assert sol.status is Status.SCALED
    assert sol.scale == pytest.approx(truth, abs=1e-7)


def test_the_reference_step_near_a_singularity_is_feasible_not_optimal() -> None:
    """cond(A) ~ 2e6: the pseudoinverse step is not the minimiser of Eq. 37 over the
    equality (the exact one is 8e-6 lower); the certificate says FEASIBLE, never OPTIMAL."""
    problem = load("ref_near_singular")
    sol = get_solver("reference").solve(problem)
    assert sol.status is not Status.OPTIMAL
    # The exact minimiser over the equality alone, from its KKT system (independent).
    n, m = problem.n, problem.m
    K = np.block([[np.diag(problem.weights), problem.A.T], [problem.A, np.zeros((m, m))]])
    rhs = np.concatenate([problem.weights * problem.center, problem.b])
    x_star = np.linalg.lstsq(K, rhs, rcond=None)[0][:n]
    assert problem.objective(x_star) < problem.objective(sol.x)


def test_a_scaled_answer_keeps_the_equality_of_its_scaled_task() -> None:
    """A SCALED answer used to pass with a residual of 3e-6, judged against the unscaled
    b, and command 1,810 rad/s along a near-null direction."""
    problem = load("scaled_eq_tol")
    for name in ("nullspace", "qp:daqp"):
        if name not in available_solvers():
            continue
        sol = solve_step(get_solver(name), problem, "scale")
        if sol.status is Status.SCALED:
            rhs = sol.scale * problem.b
            assert np.abs(problem.A @ sol.x - rhs).max() <= 1e-7 * max(1.0, np.abs(rhs).max())
        assert np.abs(sol.x).max() < 100.0, (name, sol.status, np.abs(sol.x).max())
