"""SNS: the largest feasible task scale, the centring term, the policies, truthful statuses."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from solver_cases import lp_max_scale, random_problem, reference_qp, relative_error

from dualarm_qp.errors import InfeasibleStepError
from dualarm_qp.solvers import Status, get_solver, solve_step
from dualarm_qp.step.problem import StepProblem

seeds = st.integers(min_value=0, max_value=2**32 - 1)
SNS = get_solver("sns")


def stretched(seed: int, factor: float, shift: float, n: int = 7,
              ) -> StepProblem:
    """A random step with b multiplied by ``factor`` and the boxes shifted by ``shift``
    (a shift can exclude 0 from a box, so that not even s = 0 is feasible)."""
    p = random_problem(np.random.default_rng(seed), n=n, n_grasp=n - 6)
    return StepProblem(A=p.A, b=factor * p.b, weights=p.weights, center=p.center,
                       lower=p.lower + shift, upper=p.upper + shift, n_grasp=n - 6)


def grasp_outside(seed: int, n: int = 7) -> StepProblem:
    """A feasible step whose grasp starts 0.4 mm above its range (dt = 10 ms).

    As the step builder makes it: the box ``[-v, 0]`` forbids moving further out (speed
    limit v = 0.05 m/s) and the centre, the middle of the 0.2 m range, pulls it back.
    """
    rng = np.random.default_rng(seed)
    p = random_problem(rng, n=n, n_grasp=1)
    lower, upper, center = p.lower.copy(), p.upper.copy(), p.center.copy()
    lower[-1], upper[-1], center[-1] = -0.05, 0.0, -(0.1 + 0.0004) / 0.01
    x_f = rng.uniform(lower, upper)
    return dataclasses.replace(p, b=p.A @ x_f, lower=lower, upper=upper, center=center)


def assert_verifies(problem: StepProblem, x: np.ndarray, scale: float) -> None:
    """``A x = scale b`` and the bounds, to 1e-9."""
    b_scale = max(1.0, float(np.abs(problem.b).max()))
    assert float(np.abs(problem.A @ x - scale * problem.b).max()) <= 1e-9 * b_scale
    assert float(np.maximum(problem.lower - x, x - problem.upper).max()) <= 1e-9


@settings(max_examples=150, deadline=None)
@given(seed=seeds, factor=st.floats(0.5, 20.0), shift=st.sampled_from([0.0, 0.0, 0.3]),
       n=st.sampled_from([7, 7, 8]))
@pytest.mark.slow
def test_scale_policy_reaches_the_lp_scale(seed: int, factor: float, shift: float,
                                           n: int) -> None:
    """Through solve_step("scale"): the full task when feasible, else SCALED at the LP's
    largest scale within 1e-9, RELAXED when no s works."""
    problem = stretched(seed, factor, shift, n)
    full = lp_max_scale(problem)
    sol = solve_step(SNS, problem, "scale")
    assert np.isfinite(sol.x).all()
    if full is None:
        assert sol.status is Status.RELAXED, (sol.status, sol.message)
        return
    if full >= 1.0 - 1e-9:
        assert sol.status in (Status.OPTIMAL, Status.FEASIBLE), (sol.status, sol.message)
        assert sol.scale == 1.0
    else:
        expected = full
        assert sol.status is Status.SCALED, (sol.status, sol.message)
        assert abs(sol.scale - expected) <= 1e-9, (sol.scale, expected)
    assert_verifies(problem, sol.x, sol.scale)


@settings(max_examples=60, deadline=None)
@given(seed=seeds, factor=st.floats(1.5, 20.0), n=st.sampled_from([7, 8]))
def test_solve_reports_the_infeasible_full_task(seed: int, factor: float, n: int) -> None:
    """SNS alone never scales: INFEASIBLE with the exact largest scale in extras, and
    on the task scaled to that largest scale (what the policy hands it) scale 1."""
    problem = stretched(seed, factor, 0.0, n)
    expected = lp_max_scale(problem)
    assert expected is not None  # the boxes hold 0: s = 0 is feasible
    sol = SNS.solve(problem)
    if expected >= 1.0 - 1e-9:
        assert sol.status in (Status.OPTIMAL, Status.FEASIBLE)
        return
    assert sol.status is Status.INFEASIBLE
    assert abs(sol.extras["max_scale"] - expected) <= 1e-9
    assert sol.extras["conflicts"]
    assert not sol.x.any()
    scaled = dataclasses.replace(problem, b=sol.extras["max_scale"] * problem.b)
    inner = SNS.solve(scaled)
    assert inner.status in (Status.OPTIMAL, Status.FEASIBLE), inner.message
    assert inner.scale == 1.0
    assert_verifies(scaled, inner.x, 1.0)


@settings(max_examples=80, deadline=None)
@given(seed=seeds, n=st.sampled_from([7, 8]),
       kind=st.sampled_from(["random", "pinched grasp", "grasp outside", "holds zero"]))
def test_every_answer_verifies_and_its_status_is_true(seed: int, n: int, kind: str) -> None:
    """Feasible steps: always the full task; OPTIMAL is the QP optimum (1e-6), FEASIBLE
    meets A x = b and the bounds and is no better than the optimum."""
    rng = np.random.default_rng(seed)
    problem = random_problem(rng, n=n, n_grasp=n - 6)
    if kind == "pinched grasp":
        x_f = np.linalg.lstsq(problem.A[:, :6], problem.b, rcond=None)[0]
        lower = np.concatenate([x_f - rng.uniform(0.05, 1.0, 6), np.zeros(n - 6)])
        upper = np.concatenate([x_f + rng.uniform(0.05, 1.0, 6), np.zeros(n - 6)])
        problem = dataclasses.replace(problem, lower=lower, upper=upper)
    elif kind == "grasp outside":
        problem = grasp_outside(seed, n)
    elif kind == "holds zero":
        problem = dataclasses.replace(problem, lower=np.minimum(problem.lower, 0.0),
                                      upper=np.maximum(problem.upper, 0.0))
    ref = reference_qp(problem)
    if ref is None:  # degenerate for the enumeration (rare): nothing to compare with
        return
    sol = SNS.solve(problem)
    assert sol.status in (Status.OPTIMAL, Status.FEASIBLE), (sol.status, sol.message)
    assert sol.scale == 1.0
    assert_verifies(problem, sol.x, 1.0)
    if sol.status is Status.OPTIMAL:
        assert relative_error(sol.x, ref) < 1e-6
    else:
        assert problem.objective(sol.x) >= problem.objective(ref) * (1 - 1e-9)
        assert sol.message


def test_one_null_direction_gives_the_qp_optimum() -> None:
    """6 x 7: any point of the segment SNS ends on is the QP optimum; it says OPTIMAL."""
    rng = np.random.default_rng(21)
    for _ in range(40):
        problem = random_problem(rng)
        ref = reference_qp(problem)
        assert ref is not None
        sol = SNS.solve(problem)
        assert sol.status is Status.OPTIMAL, sol.message
        assert relative_error(sol.x, ref) < 1e-6


def test_two_null_directions_can_differ_from_the_qp_optimum() -> None:
    """6 x 8: SNS never releases a saturated bound, so it sometimes stops at a point
    that is not the optimum, and then says FEASIBLE (with what it held)."""
    rng = np.random.default_rng(22)
    statuses = []
    for _ in range(60):
        problem = random_problem(rng, n=8, n_grasp=2)
        sol = SNS.solve(problem)
        statuses.append(sol.status)
        if sol.status is Status.FEASIBLE:
            assert sol.extras["saturated"]
            assert "held" in sol.message
    assert Status.FEASIBLE in statuses
    assert Status.OPTIMAL in statuses


@settings(max_examples=60, deadline=None)
@given(seed=seeds, n=st.sampled_from([7, 8]))
def test_centring_pulls_an_outside_grasp_back(seed: int, n: int) -> None:
    """A grasp above its range on a feasible step moves back (m < 0) whenever the box
    allows it; the exact QP is the judge of that."""
    problem = grasp_outside(seed, n)
    exact = get_solver("nullspace").solve(problem)
    sol = solve_step(SNS, problem, "scale")
    assert sol.status in (Status.OPTIMAL, Status.FEASIBLE), (sol.status, sol.message)
    assert sol.x[-1] <= 0.0
    if exact.status is Status.OPTIMAL and exact.x[-1] < -1e-9:
        assert sol.x[-1] < -1e-9, (sol.x[-1], exact.x[-1])


def test_centring_is_kept_when_the_greedy_order_fails() -> None:
    """Seed set where the saturation order of plain SNS misses the full task: the
    completion still follows the centres (no fall-back to c = 0)."""
    completed = 0
    for seed in range(60):
        problem = grasp_outside(seed, 8)
        sol = SNS.solve(problem)
        if sol.extras["completed"]:
            completed += 1
            assert sol.x[-1] < -1e-9
    assert completed > 0


def test_relax_gives_relaxed() -> None:
    problem = stretched(3, 5.0, 0.0)
    assert lp_max_scale(problem) < 1.0  # type: ignore[operator]
    sol = solve_step(SNS, problem, "relax")
    assert sol.status is Status.RELAXED, (sol.status, sol.message)
    assert sol.extras["policy"] == "relax"
    assert sol.bound_violation <= 1e-9
    assert sol.eq_residual > 1e-3


@pytest.mark.parametrize("shift", [0.0, 0.3])
def test_stop_raises(shift: float) -> None:
    problem = stretched(4, 5.0, shift)
    expected = lp_max_scale(problem)
    assert expected is None or expected < 1.0
    with pytest.raises(InfeasibleStepError) as info:
        solve_step(SNS, problem, "stop")
    assert info.value.conflicts
    assert all(c.split()[0] in problem.names for c in info.value.conflicts)


def test_feasible_step_is_the_same_under_every_policy() -> None:
    problem = random_problem(np.random.default_rng(5))
    direct = SNS.solve(problem)
    assert direct.status.usable
    for policy in ("scale", "relax", "stop"):
        sol = solve_step(SNS, problem, policy)  # type: ignore[arg-type]
        assert sol.status is direct.status
        assert np.array_equal(sol.x, direct.x)


def test_box_without_zero_is_solved() -> None:
    """The original SNS needs x = 0 in the box; this one does not."""
    rng = np.random.default_rng(6)
    for _ in range(20):
        p = random_problem(rng)
        x_f = rng.uniform(p.lower, p.upper)
        lower = np.maximum(p.lower, x_f - 0.05) + 0.0
        upper = np.minimum(p.upper, x_f + 0.05)
        lower[0], upper[0] = x_f[0] - 0.01, x_f[0] + 0.01
        if lower[0] <= 0.0 <= upper[0]:
            continue
        problem = dataclasses.replace(p, b=p.A @ x_f, lower=lower, upper=upper)
        sol = SNS.solve(problem)
        assert sol.status in (Status.OPTIMAL, Status.FEASIBLE), sol.message
        assert_verifies(problem, sol.x, 1.0)
