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
from dualarm_qp.solvers import get_solver
from dualarm_qp.solvers._kkt import refine
from dualarm_qp.solvers.backends import NATIVE
from dualarm_qp.step.problem import StepProblem

SUITE = Path(__file__).resolve().parents[2] / "benchmarks" / "data" / "step_suite.npz"

#: Every 7th instance of the suite (rollout, scaled, pinched and infeasible kinds).
STRIDE = 7


def _rel(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.abs(a - b).max()) / max(1.0, float(np.abs(b).max()))


def _backend_points(backend: str) -> list[tuple[int, StepProblem, np.ndarray]]:
    """Each instance of the subset with the native backend's last iterate, plus two
    perturbations of it (which exercise the rejections)."""
    if backend not in NATIVE:
        pytest.skip(f"{backend} is not installed")
    suite = load_suite(SUITE)
    name = {"osqp": "qp:osqp", "proxqp": "qp:proxsuite"}[backend]
    native = NATIVE[backend](get_solver(name).options)
    rng = np.random.default_rng(3)
    out = []
    for i in range(0, len(suite), STRIDE):
        p = suite.problems[i]
        if (p.lower > p.upper).any():
            continue
        ans = native.solve(p)
        if ans.x is None:
            continue
        x = ans.x
        out += [(i, p, x), (i, p, x + 1e-5 * rng.standard_normal(p.n)),
                (i, p, np.clip(x + 1e-3 * rng.standard_normal(p.n), p.lower, p.upper))]
    return out


@pytest.mark.parametrize("backend", ["osqp", "proxqp"])
def test_certificate_accepts_only_the_optimum(backend: str) -> None:
    """Whatever the certificate accepts near a backend's answer is the exact optimum to
    1e-12, and only on feasible steps; the subset exercises acceptance and rejection."""
    suite = load_suite(SUITE)
    exact = get_solver("nullspace")
    counts = {"accepted": 0, "rejected": 0}
    for i, p, x in _backend_points(backend):
        got = refine(p, x)
        if got is None:
            counts["rejected"] += 1
            continue
        assert suite.feasible[i], f"instance {i}: a certificate for an infeasible step"
        assert _rel(got, exact.solve(p).x) <= 1e-12, f"instance {i}"
        counts["accepted"] += 1
    assert counts["accepted"] > 50 and counts["rejected"] > 50, counts


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


def test_interior_guess_outside_the_box_is_rejected() -> None:
    """No bound guessed active, but the unconstrained optimum breaks x1 >= 0.6."""
    p = _line_problem()
    assert refine(p, np.array([0.9, 0.1])) is None


def test_zero_width_box_and_larger_null_space_are_certified() -> None:
    rng = np.random.default_rng(5)
    A = rng.standard_normal((6, 8))
    x_star = rng.uniform(-0.5, 0.5, 8)
    p = StepProblem(A=A, b=A @ x_star, weights=rng.uniform(1, 10, 8), center=np.zeros(8),
                    lower=np.full(8, -1.0), upper=np.full(8, 1.0), n_grasp=1)
    x = x_star + 1e-3 * rng.standard_normal(8)
    exact = get_solver("nullspace")
    got = refine(p, x)
    assert got is not None
    assert _rel(got, exact.solve(p).x) <= 1e-12
    A7 = A[:, :7]
    lower, upper = np.full(7, -1.0), np.full(7, 1.0)
    lower[2] = upper[2] = x_star[2]  # a pinned joint
    q = StepProblem(A=A7, b=A7 @ x_star[:7], weights=np.ones(7), center=np.zeros(7),
                    lower=lower, upper=upper, n_grasp=1)
    got = refine(q, x_star[:7].copy())
    assert got is not None and got[2] == x_star[2]
    assert _rel(got, exact.solve(q).x) <= 1e-12


def test_more_rows_than_variables_with_a_pinned_box() -> None:
    """A general row's index is a row of G: with more rows than variables (24 torque rows
    on 13 variables) and a pinned box, the refinement must not look rows up as boxes."""
    n, p = 3, 7
    rng = np.random.default_rng(2)
    G = rng.normal(size=(p, n))
    lower = np.array([-1.0, 0.25, -1.0])
    upper = np.array([1.0, 0.25, 1.0])  # x1 pinned
    problem = StepProblem(np.array([[1.0, 1.0, 1.0]]), np.array([0.5]), np.ones(n),
                          np.zeros(n), lower, upper, G=G, h=np.full(p, 10.0))
    x = get_solver("nullspace").solve(problem).x
    assert x is not None
    out = refine(problem, x + 1e-9)
    assert out is not None
    np.testing.assert_allclose(out, x, atol=1e-9)
