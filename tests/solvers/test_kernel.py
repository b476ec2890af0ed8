"""The compiled kernel (``dualarm_qp._kernel``) against independent solvers.

* the exact step solver against daqp (through qpsolvers) on random steps with null-space
  dimension 0, 1 and 2 to 5, boxes and general rows, feasible by construction or
  infeasible by two contradicting rows;
* the rank decision on matrices whose smallest singular value is put well below or
  well above ``RANK_RTOL``;
* the Lawson-Hanson NNLS against ``scipy.optimize.nnls``;
* the import refuses a missing or stale kernel with a message that says what to run.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import qpsolvers
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import nnls

from dualarm_qp._compiled import SOURCES, check_fresh, kernel, source_hash
from dualarm_qp.errors import KernelError
from dualarm_qp.solvers import Status
from dualarm_qp.solvers._affine import RANK_RTOL, factor
from dualarm_qp.solvers.certify import certify, residuals
from dualarm_qp.solvers.nullspace import NullspaceSolver
from dualarm_qp.step.problem import StepProblem

seeds = st.integers(min_value=0, max_value=2**32 - 1)
ROOT = Path(__file__).resolve().parents[2]


def _step(seed: int, d: int, dense: bool, infeasible: bool) -> StepProblem:
    """A random step with null-space dimension ``d``, feasible unless ``infeasible``."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(max(d, 2), 10)) if d else int(rng.integers(2, 9))
    m = n - d
    A = rng.normal(size=(m, n))
    x_in = rng.uniform(-0.5, 0.5, n)  # strictly inside the boxes
    lower = -rng.uniform(0.6, 2.0, n)
    upper = rng.uniform(0.6, 2.0, n)
    p = int(rng.integers(0, 4))
    G = rng.normal(size=(p, n))
    h = G @ x_in + rng.uniform(0.05, 1.0, p)
    if infeasible:  # g x <= -1 and -g x <= -1: no x meets both
        g = rng.normal(size=n)
        G = np.vstack([G, g, -g])
        h = np.concatenate([h, [-1.0, -1.0]])
    if dense:
        B = rng.normal(size=(n, n))
        weights = B @ B.T + n * np.eye(n)
    else:
        weights = 10.0 ** rng.uniform(-1, 3, n)
    return StepProblem(A=A, b=A @ x_in, weights=weights, center=rng.normal(0, 3, n),
                       lower=lower, upper=upper, G=G, h=h)


def _daqp(problem: StepProblem) -> np.ndarray | None:
    W = problem.weight_matrix()
    return qpsolvers.solve_qp(
        2.0 * W, -2.0 * W @ problem.center, problem.G if problem.p else None,
        problem.h if problem.p else None, problem.A, problem.b, problem.lower,
        problem.upper, solver="daqp")


@settings(max_examples=80, deadline=None)
@given(seed=seeds, d=st.sampled_from([0, 1, 2, 3, 5]), dense=st.booleans())
def test_exact_solver_agrees_with_daqp(seed: int, d: int, dense: bool) -> None:
    problem = _step(seed, d, dense, infeasible=False)
    sol = NullspaceSolver().solve(problem)
    assert sol.status is Status.OPTIMAL, sol.message
    assert sol.extras["nullity"] == d
    assert certify(problem, sol).status is Status.OPTIMAL
    ref = _daqp(problem)
    assert ref is not None
    assert np.abs(sol.x - ref).max() <= 1e-7 * max(1.0, float(np.abs(ref).max()))


@settings(max_examples=80, deadline=None)
@given(seed=seeds, d=st.sampled_from([0, 1, 2, 4]), dense=st.booleans())
def test_exact_solver_proves_infeasibility(seed: int, d: int, dense: bool) -> None:
    problem = _step(seed, d, dense, infeasible=True)
    sol = NullspaceSolver().solve(problem)
    assert sol.status is Status.INFEASIBLE
    assert sol.extras["conflicts"]
    assert _daqp(problem) is None


@settings(max_examples=100, deadline=None)
@given(seed=seeds, exponent=st.floats(-16.0, -11.0) | st.floats(-7.0, -2.0))
def test_rank_decision_under_perturbation(seed: int, exponent: float) -> None:
    """The smallest singular value at 10**exponent of the largest: dropped below
    RANK_RTOL (1e-9) by two decades or more, kept above it by two decades or more."""
    rng = np.random.default_rng(seed)
    m, n = 6, int(rng.integers(6, 9))
    U, _ = np.linalg.qr(rng.normal(size=(m, m)))
    V, _ = np.linalg.qr(rng.normal(size=(n, n)))
    sv = np.sort(rng.uniform(1.0, 5.0, m))[::-1]
    sv[-1] = sv[0] * 10.0**exponent
    A = U @ np.diag(sv) @ V[:m]
    f = factor(A)
    expected = m if 10.0**exponent > RANK_RTOL else m - 1
    assert f.rank == expected
    assert f.nullity == n - expected
    assert np.abs(A @ f.N).max(initial=0.0) <= 1e-9 * sv[0]
    assert np.abs(f.N.T @ f.N - np.eye(f.nullity)).max(initial=0.0) <= 1e-12


@settings(max_examples=100, deadline=None)
@given(seed=seeds, m=st.integers(1, 12), n=st.integers(1, 8))
def test_nnls_agrees_with_scipy(seed: int, m: int, n: int) -> None:
    rng = np.random.default_rng(seed)
    A = rng.normal(size=(m, n))
    b = rng.normal(size=m) * 3.0
    out = kernel.nnls(A, b, 50 * (n + 1))
    x, rnorm, converged = out.x, out.rnorm, out.converged
    ref, ref_norm = nnls(A, b, maxiter=50 * (n + 1))
    assert converged
    assert (x >= 0.0).all()
    assert abs(rnorm - ref_norm) <= 1e-10 * max(1.0, ref_norm)
    assert abs(rnorm - np.linalg.norm(A @ x - b)) <= 1e-12 * max(1.0, ref_norm)
    if m >= n:  # full column rank (almost surely): the minimiser is unique
        assert np.abs(x - ref).max() <= 1e-9 * max(1.0, float(np.abs(ref).max()))


def test_nnls_converges_when_the_answer_is_large() -> None:
    """b in the cone of nearly dependent columns: x ~ 900 for |b| ~ 3, the residual zero
    to rounding (the fixed tolerance alone kept adding columns to it until the limit)."""
    rng = np.random.default_rng(189822818)
    A = rng.normal(size=(2, 7))
    b = rng.normal(size=2) * 3.0
    out = kernel.nnls(A, b, 50 * 8)
    x, rnorm = out.x, out.rnorm
    assert out.converged and (x >= 0.0).all() and x.max() > 100.0
    assert rnorm <= 1e-10 and abs(rnorm - nnls(A, b)[1]) <= 1e-10


def test_nnls_zero_and_nonpositive_answers() -> None:
    A = np.eye(3)
    out = kernel.nnls(A, np.array([-1.0, 2.0, 0.0]), 20)
    assert out.converged
    assert out.x.tolist() == [0.0, 2.0, 0.0]
    assert out.rnorm == pytest.approx(1.0)


def test_a_stale_kernel_is_refused(tmp_path: Path) -> None:
    for source in SOURCES.iterdir():
        (tmp_path / source.name).write_bytes(source.read_bytes())
    check_fresh(tmp_path)  # the same sources: the built kernel is theirs
    assert source_hash(tmp_path) == kernel.SOURCE_HASH
    with (tmp_path / "nnls.cpp").open("a") as fh:
        fh.write("// edited\n")
    with pytest.raises(KernelError, match=r"stale.*pip install --no-build-isolation -e \."):
        check_fresh(tmp_path)
    check_fresh(tmp_path / "absent")  # an installed wheel has no sources: nothing to check


def test_a_missing_kernel_says_how_to_build_it() -> None:
    """``import dualarm_qp`` loads no kernel (its names load on first use): the first
    name that needs it raises."""
    code = ("import sys; sys.modules['dualarm_qp._kernel'] = None\n"
            "import dualarm_qp\n"
            "try:\n    dualarm_qp.puma560\nexcept ImportError as e:\n"
            "    from dualarm_qp.errors import DualArmError\n"
            "    print(type(e).__name__, isinstance(e, DualArmError), e)\n")
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env=env, check=True, timeout=60).stdout
    assert out.startswith("KernelError True")
    assert "pip install --no-build-isolation -e ." in out


@settings(max_examples=30, deadline=None)
@given(seed=seeds, d=st.sampled_from([1, 2, 3]), scale=st.floats(0.1, 0.9))
def test_a_known_factor_gives_the_same_answer(seed: int, d: int, scale: float) -> None:
    """A scaled step reuses the factor of its unscaled one: the answer is bit for bit the
    one computed from scratch."""
    problem = _step(seed, d, False, infeasible=False)
    solver = NullspaceSolver()
    solver.solve(problem)  # caches the factor of A
    reused = solver.solve(problem.scaled(scale))
    fresh = solver.solve(StepProblem(A=problem.A, b=scale * problem.b,
                                     weights=problem.weights, center=problem.center,
                                     lower=problem.lower, upper=problem.upper,
                                     G=problem.G, h=problem.h))
    assert reused.status is fresh.status
    assert np.array_equal(reused.x, fresh.x)


def test_residuals_of_a_non_finite_x_are_not_numbers() -> None:
    problem = _step(3, 1, False, infeasible=False)
    x = np.zeros(problem.n)
    x[0] = np.nan
    eq, viol = residuals(problem, x)
    assert np.isnan(eq) and np.isnan(viol)
    assert residuals(problem, np.zeros(problem.n))[0] == float(np.abs(problem.b).max())
