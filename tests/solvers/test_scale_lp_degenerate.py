"""The task-scale LP on degenerate steps, against HiGHS and a scale feasible by construction.

The LP (``src/kernel/scale_lp.cpp``) used to answer "no feasible scale" on feasible
steps where ``x = 0`` is infeasible and the optimum is a degenerate vertex: a pinned
variable or two opposite rows (a single feasible scale) gave a dual ray made of a
1e-12 rounding violation, and nearly opposite rows a basis so ill-conditioned that its
multipliers' rounding (1e-9) looked like violated rows, ending in a false ray or in
cycling to the iteration limit. Then a QP backend's failure was called INFEASIBLE on a
step the exact solver solves, the ``stop`` policy raised instead of handing the step to
its fallback, and the ``scale`` policy relaxed a step it could have scaled.

The steps come from :mod:`degenerate_lp`; the references are SciPy's HiGHS on the same
LP written in ``x`` (independent of the library's reduction to the null space) and the
scale ``s_true`` at which a point meets every row by construction.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from degenerate_lp import degenerate_step, highs_scale
from scipy.optimize import linprog

from dualarm_qp.solvers import Status, available_solvers, get_solver, solve_step
from dualarm_qp.solvers._scale import _lp, max_task_scale
from dualarm_qp.step.problem import StepProblem

DATA = Path(__file__).parent / "data" / "scale_lp_degenerate.npz"

#: Agreement of the largest scale with HiGHS's (dimensionless). Both are exact up to
#: their feasibility tolerances (1e-9 of a row in units of x here, 1e-7 in HiGHS) on
#: steps whose largest scale is well-posed (see degenerate_lp).
SCALE_TOL = 1e-7

#: Largest violation of a general row by the LP's point [units of x, unit-norm rows].
ROW_TOL = 1e-8


def _check_step(seed: int) -> bool:
    """Check one random degenerate step; whether HiGHS answered (it always did so far)."""
    problem, s_true = degenerate_step(np.random.default_rng(seed))
    reach = max_task_scale(problem)
    assert reach.scale is not None and reach.x is not None, (seed, reach.blocking)
    s, x = reach.scale, reach.x
    assert s >= s_true - 1e-9, (seed, s, s_true)
    rhs = s * problem.b
    assert np.abs(problem.A @ x - rhs).max() <= 1e-9 * max(1.0, float(np.abs(rhs).max()))
    assert np.all((problem.lower <= x) & (x <= problem.upper))
    norms = np.linalg.norm(problem.G, axis=1)
    assert float(((problem.G @ x - problem.h) / norms).max()) <= ROW_TOL, seed
    reference = highs_scale(problem)
    if reference is None:
        return False
    assert s == pytest.approx(reference, abs=SCALE_TOL), seed
    return True


def test_degenerate_steps_have_the_largest_scale_highs_finds() -> None:
    """100 random degenerate steps (3 of which gave "no feasible scale", or 0.81 where
    0.82 is feasible, before)."""
    answered = [_check_step(seed) for seed in range(100)]
    assert sum(answered) >= 95


@pytest.mark.slow
def test_degenerate_steps_have_the_largest_scale_highs_finds_many() -> None:
    """2,000 more (14 of which gave "no feasible scale", or a smaller scale, before)."""
    answered = [_check_step(seed) for seed in range(100, 2100)]
    assert sum(answered) >= 1900


def _recorded() -> dict[str, tuple[np.ndarray, np.ndarray, np.ndarray, float]]:
    with np.load(DATA) as z:
        names = sorted({key.rsplit("_", 1)[0] for key in z.files if key.endswith("_M")})
        return {name: (z[f"{name}_M"], z[f"{name}_a"], z[f"{name}_g"],
                       float(z[f"{name}_s_true"])) for name in names}


RECORDED = _recorded()


@pytest.mark.parametrize("name", sorted(RECORDED))
def test_recorded_degenerate_lps_are_solved(name: str) -> None:
    """LPs ``max s, M t + a s <= g`` of degenerate steps (reduced by the library's basis).

    ``opposite_pair_ray`` (two opposite rows: a single feasible scale) and
    ``pinned_pair_ray`` (a pinned variable) ended in a dual ray made of rounding;
    ``near_opposite_ray`` and ``near_opposite_cycle`` (rows 1e-13 to 1e-7 from opposite,
    through the optimal vertex) in a ray or a cycle made of the rounding of a nearly
    singular basis. ``s_true`` is feasible by construction; HiGHS solves the same LP.
    """
    M, a, g, s_true = RECORDED[name]
    got = _lp(M, a, g, 0.0, 1.0)
    assert got is not None, "iteration limit"
    ok, t, s, _ = got
    assert ok, "no feasible scale"
    assert s >= s_true - 1e-9
    assert float((M @ t + a * s - g).max()) <= ROW_TOL
    d = M.shape[1]
    ref = linprog(np.r_[np.zeros(d), -1.0], A_ub=np.c_[M, a], b_ub=g,
                  bounds=[(None, None)] * d + [(0.0, 1.0)], method="highs")
    assert ref.status == 0 and s == pytest.approx(-ref.fun, abs=1e-8)


def _step(seed: int) -> tuple[StepProblem, float]:
    return degenerate_step(np.random.default_rng(seed))


#: A step feasible at full scale, with two pinned variables (x1, x11) and x = 0 outside
#: the box; the LP used to call it infeasible, blocked by "x1 lower" among others.
FULL = 1283
#: A step feasible up to s = 0.0987 (x = 0 infeasible, x4 pinned); the LP found no scale.
PARTIAL = 25


def test_a_backend_failure_on_a_feasible_step_is_not_called_infeasible() -> None:
    """A QP backend that fails on a feasible degenerate step reports ERROR ("the step is
    feasible"), never INFEASIBLE, and the exact solver solves the step."""
    problem, s_true = _step(FULL)
    assert s_true == 1.0 and highs_scale(problem) == pytest.approx(1.0, abs=1e-9)
    assert max_task_scale(problem).full
    assert get_solver("nullspace").solve(problem).status is Status.OPTIMAL
    for name in [n for n in available_solvers() if n.startswith("qp:")]:
        sol = get_solver(name).solve(problem)
        assert sol.status is not Status.INFEASIBLE, (name, sol.message)


@pytest.mark.skipif("qp:quadprog" not in available_solvers(), reason="quadprog missing")
def test_the_stop_policy_hands_a_feasible_step_to_its_fallback() -> None:
    """quadprog fails this step (it used to be INFEASIBLE, and "stop" raised naming the
    pinned x1): the step is feasible, so the fallback solves it."""
    problem, _ = _step(FULL)
    failed = get_solver("qp:quadprog").solve(problem)
    assert failed.status is Status.ERROR and "the step is feasible" in failed.message
    sol = solve_step(get_solver("qp:quadprog"), problem, "stop",
                     fallback=get_solver("nullspace"))
    assert sol.status is Status.OPTIMAL
    assert sol.extras["fallback"]["to"] == "nullspace"


def test_the_scale_policy_scales_a_step_it_used_to_relax() -> None:
    """The largest scale is 0.0987: the policy scales the task (it used to relax it,
    leaving an equality error of 40)."""
    problem, s_true = _step(PARTIAL)
    truth = highs_scale(problem)
    assert truth is not None and truth == pytest.approx(s_true, abs=1e-9)
    sol = solve_step(get_solver("nullspace"), problem, "scale")
    assert sol.status is Status.SCALED
    assert sol.scale == pytest.approx(truth, abs=SCALE_TOL)
    rhs = sol.scale * problem.b
    assert np.abs(problem.A @ sol.x - rhs).max() <= 1e-9 * max(1.0, np.abs(rhs).max())
