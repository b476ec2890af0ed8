"""The step-instance suite: the committed data, scoring rules, and the generator."""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import numpy as np
import pytest

from dualarm_qp.bench.suite import (
    PROFILES,
    SolverRun,
    is_solved,
    load_suite,
    run_solver,
    save_suite,
    score,
    shifted_geometric_mean,
)
from dualarm_qp.solvers import Status
from dualarm_qp.step.problem import StepProblem

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "benchmarks" / "data" / "step_suite.npz"


@pytest.fixture(scope="module")
def suite():  # type: ignore[no-untyped-def]
    return load_suite(DATA)


def test_committed_suite_is_small_and_varied(suite) -> None:  # type: ignore[no-untyped-def]
    assert DATA.stat().st_size < 4e6
    assert 2000 <= len(suite) <= 5000
    assert {p.A.shape for p in suite.problems} == {(12, 13)}
    share = float((~suite.feasible).mean())
    assert 0.05 < share < 0.5
    assert {"rollout", "rollout_infeasible", "pinched", "empty_box"} <= set(suite.kind)
    assert np.isfinite(suite.objective_star[suite.feasible]).all()
    assert len(suite.meta["scenarios"]) >= 20
    # s7 as the shipped configs mean it (grasp_unit: m): 1, 100 or 1000 in SI.
    assert {sc["grasp_weight_unit"] for sc in suite.meta["scenarios"]} == {"m"}
    s7 = np.array([p.weights[-1] for p in suite.problems])
    assert set(np.unique(s7).tolist()) <= {1.0, 100.0, 1000.0}


def test_reduced_suite_scores(suite) -> None:  # type: ignore[no-untyped-def]
    small = suite.subset(np.arange(0, len(suite), 40))
    runs = [run_solver(small, s) for s in ("nullspace", "qp:daqp", "reference")]
    rows = {r["solver"]: r for r in score(small, runs, PROFILES["default"])}
    assert rows["nullspace"]["success_rate"] == 1.0
    assert rows["nullspace"]["claimed_true_rate"] == 1.0
    # The paper's step ignores the bounds: it never detects an infeasible instance.
    assert rows["reference"]["infeasible_detected"] == 0.0
    assert rows["reference"]["success_rate"] < 1.0
    assert min(r["sgm_time_rel"] for r in rows.values()) == 1.0
    for r in rows.values():
        assert 0.0 <= r["success_rate"] <= 1.0


def _problem() -> StepProblem:
    A = np.hstack([np.eye(6), np.ones((6, 1))])
    return StepProblem(A=A, b=np.ones(6), weights=np.ones(7), center=np.zeros(7),
                       lower=-2 * np.ones(7), upper=2 * np.ones(7))


def test_solved_needs_status_and_residuals_and_objective() -> None:
    p = _problem()
    prof = PROFILES["default"]
    x_star = np.concatenate([np.full(6, 1 - 6 / 7), [6 / 7]])
    f_star = p.objective(x_star)
    assert is_solved(p, True, f_star, Status.OPTIMAL, x_star, prof)
    assert not is_solved(p, True, f_star, Status.INFEASIBLE, x_star, prof)  # status
    bad = x_star.copy()
    bad[0] += 1e-5
    assert not is_solved(p, True, f_star, Status.OPTIMAL, bad, prof)  # residual
    other = np.concatenate([np.zeros(6), [1.0]])  # feasible, not optimal
    assert not is_solved(p, True, f_star, Status.OPTIMAL, other, prof)
    assert is_solved(p, False, math.nan, Status.INFEASIBLE, np.zeros(7), prof)
    assert not is_solved(p, False, math.nan, Status.OPTIMAL, x_star, prof)


def test_claims_and_shifted_geometric_mean() -> None:
    p = _problem()
    x_star = np.concatenate([np.full(6, 1 - 6 / 7), [6 / 7]])
    from dualarm_qp.bench.suite import Suite

    s = Suite([p, p], np.array([True, True]), np.array([p.objective(x_star)] * 2),
              np.array(["a", "a"]), {})
    good = SolverRun("good", ["optimal", "optimal"], np.array([True, True]),
                     np.array([1e-5, 1e-5]), np.vstack([x_star, x_star]))
    liar = SolverRun("liar", ["optimal", "optimal"], np.array([True, True]),
                     np.array([1e-6, 1e-6]), np.vstack([x_star, np.zeros(7)]))
    rows = {r["solver"]: r for r in score(s, [good, liar], PROFILES["default"])}
    assert rows["good"]["claimed_true_rate"] == 1.0
    assert rows["liar"]["claimed_true_rate"] == 0.5
    assert rows["good"]["sgm_time_rel"] == 1.0 and rows["liar"]["sgm_time_rel"] > 1.0
    assert shifted_geometric_mean([1e-5, 1e-5]) == pytest.approx(1e-5)
    assert shifted_geometric_mean([0.0, 3e-5]) == pytest.approx(1e-5)


def test_generator_is_deterministic_and_round_trips(tmp_path: Path) -> None:
    spec = importlib.util.spec_from_file_location("make_suite",
                                                  ROOT / "benchmarks" / "make_suite.py")
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    a, b = tmp_path / "a.npz", tmp_path / "b.npz"
    assert mod.main(["--scenarios", "1", "--out", str(a)]) == 0
    assert mod.main(["--scenarios", "1", "--out", str(b)]) == 0
    sa, sb = load_suite(a), load_suite(b)
    assert len(sa) == len(sb) > 20
    np.testing.assert_array_equal(np.stack([p.b for p in sa.problems]),
                                  np.stack([p.b for p in sb.problems]))
    save_suite(tmp_path / "c.npz", sa.problems, sa.feasible, sa.objective_star, sa.kind,
               sa.meta)
    sc = load_suite(tmp_path / "c.npz")
    np.testing.assert_array_equal(sc.feasible, sa.feasible)
