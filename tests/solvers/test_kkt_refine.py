"""The KKT certificate (``_kkt.refine``): the closed form on the line ``x0 + t z`` against
the general equality-constrained solve, on a subset of the recorded step suite.

The reference is the exact solver (``nullspace``). The general path solves on the null
space of the free columns (SVD at ``RANK_RTOL``, then a QR least-distance solve), not on
the normal equations ``A_f W_f^-1 A_f^T`` whose condition reached 5e9 with the sliding
weight at 1e9: measured on this subset (osqp and proxqp points), both paths accept the
same points (740 / 745; the normal-equation path used to reject 1372 optima on the
whole suite) and agree to 3e-14.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from dualarm_qp.bench.suite import load_suite
from dualarm_qp.solvers import _kkt, _native, get_solver
from dualarm_qp.solvers._kkt import refine
from dualarm_qp.step.problem import StepProblem

SUITE = Path(__file__).resolve().parents[2] / "benchmarks" / "data" / "step_suite.npz"

#: Every 7th instance of the suite (rollout, scaled, pinched and infeasible kinds).
STRIDE = 7


def _rel(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.abs(a - b).max()) / max(1.0, float(np.abs(b).max()))


def _backend_points(backend: str) -> list[tuple[int, StepProblem, np.ndarray]]:
    """Each instance of the subset with the native backend's last iterate, plus two
    perturbations of it (which exercise the rejections)."""
    if backend not in _native.NATIVE:
        pytest.skip(f"{backend} is not installed")
    suite = load_suite(SUITE)
    name = {"osqp": "qp:osqp", "proxqp": "qp:proxsuite"}[backend]
    native = _native.NATIVE[backend](get_solver(name).options)
    rng = np.random.default_rng(3)
    out = []
    for i in range(0, len(suite), STRIDE):
        p = suite.problems[i]
        if (p.lower > p.upper).any():
            continue
        ans = native.solve(p)
        if ans.x is None:
            continue
        x = ans.x + p.center
        out += [(i, p, x), (i, p, x + 1e-5 * rng.standard_normal(p.n)),
                (i, p, np.clip(x + 1e-3 * rng.standard_normal(p.n), p.lower, p.upper))]
    return out


@pytest.mark.parametrize("backend", ["osqp", "proxqp"])
def test_closed_form_certifies_exactly_the_optimum(backend: str) -> None:
    """Where the general path accepts, the closed form accepts too; whatever either
    accepts is the exact optimum to 1e-12."""
    suite = load_suite(SUITE)
    exact = get_solver("nullspace")
    counts = {"both": 0, "closed_only": 0, "neither": 0}
    for i, p, x in _backend_points(backend):
        general = _kkt._refine_general(p, x)
        closed = refine(p, x)
        if closed is None:
            assert general is None, f"instance {i}: the closed form rejects a certified point"
            counts["neither"] += 1
            continue
        assert suite.feasible[i], f"instance {i}: a certificate for an infeasible step"
        ref = exact.solve(p).x
        assert _rel(closed, ref) <= 1e-12, f"instance {i}"
        if general is not None:
            assert _rel(general, closed) <= 1e-12, f"instance {i}"
            counts["both"] += 1
        else:
            counts["closed_only"] += 1
    # The subset exercises acceptance and rejection.
    assert counts["both"] > 50 and counts["neither"] > 50, counts


def _line_problem() -> StepProblem:
    """A 1 x 2 step: x1 + x2 = 1, centre 0, unit weights: the optimum is (0.5, 0.5)."""
    return StepProblem(A=np.array([[1.0, 1.0]]), b=np.array([1.0]), weights=np.ones(2),
                       center=np.zeros(2), lower=np.array([0.6, -2.0]),
                       upper=np.array([2.0, 2.0]), n_grasp=1)


def test_active_bound_with_right_sign_is_certified() -> None:
    """x1 >= 0.6 blocks the unconstrained optimum (0.5, 0.5): the optimum is (0.6, 0.4)."""
    p = _line_problem()
    out = refine(p, np.array([0.6 + 1e-12, 0.4]))
    assert out is not None
    np.testing.assert_allclose(out, [0.6, 0.4], rtol=0, atol=1e-15)


def test_wrong_sign_multiplier_is_rejected() -> None:
    """A point at the upper bound of x1, where the multiplier would pull the wrong way."""
    p = _line_problem()
    x = np.array([2.0, -1.0])
    assert refine(p, x) is None
    assert _kkt._refine_general(p, x) is None


def test_interior_guess_outside_the_box_is_rejected() -> None:
    """No bound guessed active, but the unconstrained optimum breaks x1 >= 0.6."""
    p = _line_problem()
    assert refine(p, np.array([0.9, 0.1])) is None


def test_zero_width_box_and_larger_null_space_use_the_general_path() -> None:
    rng = np.random.default_rng(5)
    A = rng.standard_normal((6, 8))
    x_star = rng.uniform(-0.5, 0.5, 8)
    p = StepProblem(A=A, b=A @ x_star, weights=rng.uniform(1, 10, 8), center=np.zeros(8),
                    lower=np.full(8, -1.0), upper=np.full(8, 1.0), n_grasp=1)
    x = x_star + 1e-3 * rng.standard_normal(8)
    np.testing.assert_array_equal(refine(p, x), _kkt._refine_general(p, x))
    A7 = A[:, :7]
    lower, upper = np.full(7, -1.0), np.full(7, 1.0)
    lower[2] = upper[2] = x_star[2]  # a pinned joint
    q = StepProblem(A=A7, b=A7 @ x_star[:7], weights=np.ones(7), center=np.zeros(7),
                    lower=lower, upper=upper, n_grasp=1)
    y = x_star[:7].copy()
    a, b = refine(q, y), _kkt._refine_general(q, y)
    assert (a is None) == (b is None)
    if a is not None and b is not None:
        np.testing.assert_array_equal(a, b)


def _rank5_step(seed: int) -> tuple[StepProblem, np.ndarray]:
    """A 6 x 7 step of rank 5 (two null directions) and its optimum (exact solver)."""
    rng = np.random.default_rng(seed)
    U, _ = np.linalg.qr(rng.standard_normal((6, 6)))
    V, _ = np.linalg.qr(rng.standard_normal((7, 7)))
    A = U[:, :5] @ np.diag(np.geomspace(1.0, 1e-2, 5)) @ V[:5]
    x_f = rng.uniform(-0.5, 0.5, 7)
    p = StepProblem(A=A, b=A @ x_f, weights=np.r_[np.ones(6), 1e4], center=np.zeros(7) + 0.4,
                    lower=x_f - 0.3, upper=x_f + 0.3, n_grasp=1)
    sol = get_solver("nullspace").solve(p)
    assert sol.extras["nullity"] == 2
    return p, sol.x


def test_two_dimensional_null_space_is_certified_by_the_general_path() -> None:
    """A 6 x 7 step of numerical rank 5: no closed form on one line; the certified point
    is the optimum on the whole null space."""
    for seed in range(10):
        p, ref = _rank5_step(seed)
        out = refine(p, ref + 1e-9)
        assert out is not None
        assert _rel(out, ref) <= 1e-10


def test_general_path_checks_stationarity_on_the_free_variables(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """A candidate whose gradient does not vanish on the free variables is rejected,
    even when every multiplier of a fixed bound has the right sign."""
    cases = []
    for seed in range(10):
        q, x = _rank5_step(seed)
        sides = (np.abs(x - q.lower) <= 1e-9, np.abs(x - q.upper) <= 1e-9,
                 np.zeros(7, dtype=bool))
        if int(sides[0].sum() + sides[1].sum()) >= 2:
            continue  # no free null direction left to test
        certified = _kkt._solve_active(q, *sides)
        assert certified is not None
        assert _rel(certified, x) <= 1e-10
        cases.append((q, sides))
    assert cases
    # The equality-constrained minimiser replaced by another point of A x = b.
    monkeypatch.setattr(_kkt, "least_distance",
                        lambda N, x0, w, c: x0 + N @ np.full(N.shape[1], 1e-3))
    for q, sides in cases:
        assert _kkt._solve_active(q, *sides) is None
