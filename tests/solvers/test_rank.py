"""Rank decisions of the exact solvers: one SVD tolerance (``_affine.RANK_RTOL``), the same
answer on every CPU.

Rank-deficient equality blocks (a redundant task row, a follower at a wrist
singularity) are perturbed well below the tolerance; the decided null-space dimension
must not change, and ``nullspace``, the KKT certificate ``refine`` and every available
``qp:*`` backend must agree with an independent reference: active-set enumeration of
the KKT system (:func:`reference`, which shares no code with the solvers) on an
equivalent full-row-rank system, built from the known factors of the test matrix (no
rank decision in the reference).
"""

from __future__ import annotations

import functools
import itertools

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from scipy.linalg import lapack
from solver_cases import lp_max_scale, random_problem, relative_error

from dualarm_qp.kinematics import puma560
from dualarm_qp.solvers import Status, available_solvers, get_solver
from dualarm_qp.solvers._affine import RANK_RTOL, affine_solutions, factor
from dualarm_qp.solvers._kkt import refine
from dualarm_qp.solvers._scale import max_task_scale
from dualarm_qp.step.problem import StepProblem

seeds = st.integers(min_value=0, max_value=2**32 - 1)

#: Relative perturbations of a rank-deficient ``A``, all far below RANK_RTOL.
PERTURBATIONS = (0.0, 1e-17, 1e-15, 1e-14, 1e-12)

#: Agreement required with the reference (relative).
AGREE = 1e-6

QP = [name for name in available_solvers() if name.startswith("qp:")]



def reference(problem: StepProblem) -> np.ndarray | None:
    """Exact minimiser by enumerating working sets of at most ``n - m`` bounds.

    ``problem.A`` must have full row rank. Each working set's KKT matrix
    ``[W A^T E^T; A 0 0; E 0 0]`` is solved only when its constraint rows ``[A; E]``
    are well conditioned (cond < 1e7): at a singular pose a bound row can lie in the
    row space of ``A`` (the null direction does not move that variable), and an LU
    solve of that singular system returns garbage that may pass the sign checks. A KKT
    point (feasible, multipliers of the right sign) of this strictly convex QP is the
    optimum; None when no well-conditioned working set gives one (a degenerate optimum).
    """
    n, m = problem.n, problem.m
    W = np.diag(problem.weights)
    for k in range(n - m + 1):
        for idx in itertools.combinations(range(n), k):
            for sides in itertools.product((-1, 1), repeat=k):
                E = np.zeros((k, n))
                E[np.arange(k), list(idx)] = 1.0
                K = np.block([[W, problem.A.T, E.T],
                              [problem.A, np.zeros((m, m + k))],
                              [E, np.zeros((k, m + k))]])
                if np.linalg.cond(np.vstack([problem.A, E])) > 1e7:
                    continue  # K is singular iff [A; E] is (W > 0)
                val = [problem.upper[i] if sd > 0 else problem.lower[i]
                       for i, sd in zip(idx, sides, strict=True)]
                rhs = np.concatenate([problem.weights * problem.center, problem.b, val])
                sol = np.linalg.solve(K, rhs)
                sol += np.linalg.solve(K, rhs - K @ sol)
                x, mu = sol[:n], sol[n + m:]
                tol = 1e-9 * max(1.0, float(np.abs(x).max()))
                if (x < problem.lower - tol).any() or (x > problem.upper + tol).any():
                    continue
                # W (x - c) + A^T lam + E^T mu = 0: lower needs mu <= 0, upper mu >= 0.
                mu_tol = 1e-9 * max(1.0, float(np.abs(mu).max(initial=0.0)))
                if (np.asarray(sides) * mu < -mu_tol).any():
                    continue
                return x
    return None


def _pert(A: np.ndarray, rel: float, rng: np.random.Generator) -> np.ndarray:
    """``A + rel ||A||_2 E`` with ``||E||_2 = 1``."""
    E = rng.standard_normal(A.shape)
    return A + rel * np.linalg.norm(A, 2) * E / np.linalg.norm(E, 2)


def _step(base: StepProblem, A: np.ndarray, x_f: np.ndarray) -> StepProblem:
    return StepProblem(A=A, b=A @ x_f, weights=base.weights, center=base.center,
                       lower=base.lower, upper=base.upper, n_grasp=base.n_grasp)


def _rank5(seed: int, n: int) -> tuple[StepProblem, np.ndarray, np.ndarray, np.ndarray]:
    """A random step whose 6 x n equality has rank 5: ``A = U5 diag(s) V5^T``.

    Returns the step data (bounds, weights, centre), ``A``, the row factor
    ``R = diag(s) V5^T`` (``A x = A x_f`` iff ``R x = R x_f``) and a box point ``x_f``.
    """
    rng = np.random.default_rng(seed)
    base = random_problem(rng, n=n, n_grasp=n - 6)
    U, _ = np.linalg.qr(rng.standard_normal((6, 6)))
    V, _ = np.linalg.qr(rng.standard_normal((n, n)))
    R = np.diag(np.geomspace(1.0, 1e-2, 5)) @ V[:5]
    x_f = rng.uniform(base.lower, base.upper)
    return base, U[:, :5] @ R, R, x_f


def _check_all(problem: StepProblem, ref: np.ndarray, rng: np.random.Generator) -> None:
    """nullspace and refine are OPTIMAL at ``ref``; no backend is OPTIMAL elsewhere."""
    sol = get_solver("nullspace").solve(problem)
    assert sol.status is Status.OPTIMAL, sol.message
    assert relative_error(sol.x, ref) < AGREE
    for x in (ref, ref + 1e-8 * rng.standard_normal(problem.n)):
        certified = refine(problem, x)
        assert certified is not None
        assert relative_error(certified, ref) < AGREE
    for name in QP:
        out = get_solver(name).solve(problem)
        assert out.status is not Status.INFEASIBLE, (name, out.message)
        if out.status is Status.OPTIMAL and out.extras.get("refined"):
            assert relative_error(out.x, ref) < AGREE, name


@pytest.mark.slow  # every backend on 25 examples: the tests below are the fast loop's
@settings(max_examples=25, deadline=None)
@given(seed=seeds, n=st.sampled_from([7, 8]))
def test_perturbed_rank_deficient_blocks(seed: int, n: int) -> None:
    """Rank 5 perturbed at 0..1e-12: nullity n - 5 every time, every answer the optimum."""
    base, A, R, x_f = _rank5(seed, n)
    ref = reference(_step(base, R, x_f))
    assume(ref is not None)  # a degenerate optimum (more than n - 5 active bounds)
    assert ref is not None
    rng = np.random.default_rng(seed % 997)
    for rel in PERTURBATIONS:
        problem = _step(base, _pert(A, rel, rng), x_f)
        aff = affine_solutions(problem.A, problem.b)
        assert aff is not None
        assert aff.nullity == n - 5, rel
        _check_all(problem, ref, rng)


def _suboptimal_on_a_line(problem: StepProblem, R: np.ndarray, x_f: np.ndarray
                          ) -> np.ndarray | None:
    """The optimum over one line ``x_f + t z`` of the two-dimensional null space:
    what the old 1-D closed form returned when dgesv hid the second direction."""
    N = factor(R).N
    z = N[:, 0]
    line = StepProblem(A=np.vstack([R, N[:, 1]]), b=np.append(R @ x_f, N[:, 1] @ x_f),
                       weights=problem.weights, center=problem.center,
                       lower=problem.lower, upper=problem.upper, n_grasp=problem.n_grasp)
    assert np.abs(line.A @ z).max() < 1e-12
    return reference(line)


@functools.cache
def _case(seed: int, n: int) -> tuple[StepProblem, np.ndarray] | None:
    """Rank-5 step (perturbed at 1e-12) and its optimum; None if degenerate."""
    base, A, R, x_f = _rank5(seed, n)
    ref = reference(_step(base, R, x_f))
    if ref is None:
        return None
    return _step(base, _pert(A, 1e-12, np.random.default_rng(seed)), x_f), ref


@pytest.mark.slow
@pytest.mark.parametrize("name", QP)
def test_no_backend_claims_optimal_for_a_suboptimal_point(name: str) -> None:
    """On 80 rank-5 steps (6 x 7 and 6 x 8, perturbed at 1e-12), OPTIMAL means the optimum.

    Strict for every answer: ``qp.QPSolver`` reports an answer that ``refine`` cannot
    certify (and that no exact backend gave) as FEASIBLE, never as OPTIMAL.
    """
    solver = get_solver(name)
    wrong = []
    for seed, n in itertools.product(range(40), (7, 8)):
        case = _case(seed, n)
        if case is None:
            continue
        problem, ref = case
        out = solver.solve(problem)
        if out.status is Status.OPTIMAL and relative_error(out.x, ref) >= AGREE:
            wrong.append((seed, n, f"{relative_error(out.x, ref):.1e}"))
    assert not wrong


@pytest.mark.parametrize("seed", range(30))
def test_refine_rejects_the_one_direction_optimum(seed: int) -> None:
    """The optimum along one null direction only (stationary on that line, not on the
    plane) is never certified as itself."""
    base, A, R, x_f = _rank5(seed, 7)
    problem = _step(base, A, x_f)
    ref = reference(_step(base, R, x_f))
    sub = _suboptimal_on_a_line(problem, R, x_f)
    if ref is None or sub is None or relative_error(sub, ref) < 1e-6:
        pytest.skip("degenerate optimum, or the line contains the optimum")
    out = refine(problem, sub)
    assert out is None or relative_error(out, ref) < AGREE


def test_lu_succeeds_on_a_numerically_singular_block() -> None:
    """dgesv factors a rounded rank-5 6 x 6 block with info = 0 (tiny last pivot); the
    old ``info == 0`` decision then took the null space as one-dimensional. The SVD
    finds both null directions and the exact optimum."""
    for seed in range(20):
        rng = np.random.default_rng(seed)
        base = random_problem(rng)
        U, _ = np.linalg.qr(rng.standard_normal((6, 6)))
        V, _ = np.linalg.qr(rng.standard_normal((6, 6)))
        block = U[:, :5] @ np.diag(np.geomspace(1.0, 0.1, 5)) @ V[:5]
        lu, _, info = lapack.dgetrf(block)[:3]
        if info == 0:
            break
    else:
        pytest.fail("no rounded rank-5 block factored without info > 0")
    pivot = float(np.abs(np.diag(lu)).min())
    assert 0.0 < pivot < 1e-14  # LU succeeds, the block is numerically singular
    A = np.hstack([block, block @ rng.standard_normal((6, 1))])  # 7th column in range
    x_f = rng.uniform(base.lower, base.upper)
    problem = _step(base, A, x_f)
    aff = affine_solutions(problem.A, problem.b)
    assert aff is not None
    assert aff.nullity == 2
    R = np.diag(np.linalg.svd(A, compute_uv=False)[:5]) @ np.linalg.svd(A)[2][:5]
    ref = reference(_step(base, R, x_f))
    assert ref is not None
    _check_all(problem, ref, rng)


# --- a follower at a wrist singularity -------------------------------------------------

def _puma(q5: float, slide: str, seed: int) -> tuple[StepProblem, np.ndarray]:
    """A PUMA 560 follower step at ``q5`` (wrist singular at 0) with one sliding column.

    ``slide = "tool_z"``: slide along the tool z axis; this direction completes the
    singular Jacobian (the 6 x 7 has full rank, only its 6 x 6 block is singular).
    ``slide = "in_range"``: a translation the arm already produces at q5 = 0; the
    6 x 7 then has rank 5 (numerically also at q5 = 1e-9: sigma_6 / sigma_1 = 2e-10).
    Returns the step and a full-row-rank system ``R x = r`` with the same solutions
    (the exact rank is known: 6, or 5 from the q5 = 0 geometry).
    """
    arm = puma560()
    q = np.array([0.3, -0.7, 0.9, 0.4, q5, -0.2])
    T, J = arm.fk_jacobian(q)
    if slide == "tool_z":
        col = np.r_[T[:3, 2], 0.0, 0.0, 0.0]
    else:
        J0 = arm.fk_jacobian(np.r_[q[:4], 0.0, q[5]])[1]
        lost = np.linalg.svd(J0)[0][:, 5]  # the twist J0 cannot produce
        d = np.cross(lost[:3], [0.0, 0.0, 1.0])
        col = np.r_[d / np.linalg.norm(d), 0.0, 0.0, 0.0]
    A = np.hstack([J, col[:, None]])
    rng = np.random.default_rng(seed)
    base = random_problem(rng)
    x_f = rng.uniform(base.lower, base.upper)
    problem = _step(base, A, x_f)
    _, s, Vt = np.linalg.svd(A)
    r = 6 if slide == "tool_z" else 5
    R = np.diag(s[:r]) @ Vt[:r]
    return problem, np.asarray(reference(_step(base, R, x_f)))


@pytest.mark.parametrize("q5", [0.0, 1e-9])
@pytest.mark.parametrize(("slide", "nullity"), [("tool_z", 1), ("in_range", 2)])
@pytest.mark.parametrize("seed", range(4))
def test_puma_wrist_singularity(q5: float, slide: str, nullity: int, seed: int) -> None:
    problem, ref = _puma(q5, slide, seed)
    if ref.shape != (problem.n,):
        pytest.skip("degenerate optimum")
    aff = affine_solutions(problem.A, problem.b)
    assert aff is not None
    assert aff.nullity == nullity
    if slide == "tool_z":  # the joint block alone is singular
        sv = np.linalg.svd(problem.A[:, :6], compute_uv=False)
        assert sv[-1] <= RANK_RTOL * sv[0]
    _check_all(problem, ref, np.random.default_rng(seed))


# --- square steps (the leader's 6 x 6) ---------------------------------------------------

def _square(seed: int, factor_b: float) -> StepProblem:
    p = random_problem(np.random.default_rng(seed), n=6, n_grasp=0)
    lower = np.minimum(p.lower, -0.05)  # 0 inside the box: s = 0 is feasible
    upper = np.maximum(p.upper, 0.05)
    return StepProblem(A=p.A, b=factor_b * p.b, weights=p.weights, center=p.center,
                       lower=lower, upper=upper, n_grasp=0)


@pytest.mark.parametrize("seed", range(10))
def test_square_step_inside_the_box(seed: int) -> None:
    problem = _square(seed, 1.0)
    x = np.linalg.solve(problem.A, problem.b)
    assert ((x >= problem.lower) & (x <= problem.upper)).all()
    sol = get_solver("nullspace").solve(problem)
    assert sol.status is Status.OPTIMAL, sol.message
    assert sol.extras["nullity"] == 0
    assert relative_error(sol.x, x) < 1e-12
    reach = max_task_scale(problem)
    assert reach.scale == 1.0
    assert reach.blocking == ()


@pytest.mark.parametrize("seed", range(10))
def test_square_step_outside_the_box(seed: int) -> None:
    """x = A^-1 b leaves the box: INFEASIBLE naming a broken bound; the task scale is the
    exact first crossing of s x along [0, 1] and names that bound."""
    problem = _square(seed, 8.0)
    x = np.linalg.solve(problem.A, problem.b)
    sol = get_solver("nullspace").solve(problem)
    assert sol.status is Status.INFEASIBLE
    assert sol.extras["conflicts"]
    for conflict in sol.extras["conflicts"]:  # every bound x breaks, each named once
        name, side = conflict.split()
        i = problem.names.index(name)
        assert (x[i] > problem.upper[i]) if side == "upper" else (x[i] < problem.lower[i])
    with np.errstate(divide="ignore"):
        ratios = np.where(x > 0, problem.upper / x, np.where(x < 0, problem.lower / x, np.inf))
    k = int(np.argmin(ratios))
    reach = max_task_scale(problem)
    assert reach.scale is not None
    # Rounding of two factorisations (the SVD here, LU above) of a matrix of condition
    # up to ~100: 1e-13 relative.
    assert abs(reach.scale - ratios[k]) <= 1e-13 * ratios[k]
    assert reach.blocking == (f"{problem.names[k]} {'upper' if x[k] > 0 else 'lower'}",)
    lp = lp_max_scale(problem)
    assert lp is not None
    assert abs(reach.scale - lp) <= 1e-7
    assert reach.x is not None
    np.testing.assert_allclose(reach.x, reach.scale * x, rtol=0, atol=1e-12)


def test_square_singular_step() -> None:
    """A 6 x 6 step of rank 5 (consistent b) has a one-dimensional null space."""
    base, A, R, x_f = _rank5(3, 6)
    problem = _step(base, A, x_f)
    aff = affine_solutions(problem.A, problem.b)
    assert aff is not None
    assert aff.nullity == 1
    ref = reference(_step(base, R, x_f))
    assert ref is not None
    _check_all(problem, ref, np.random.default_rng(3))


def test_tolerance_boundary_is_relative() -> None:
    """sigma_min / sigma_max just above / below RANK_RTOL: rank 6 / rank 5, at any scale."""
    rng = np.random.default_rng(0)
    U, _ = np.linalg.qr(rng.standard_normal((6, 6)))
    V, _ = np.linalg.qr(rng.standard_normal((7, 7)))
    for scale in (1e-3, 1.0, 1e3):
        for ratio, rank in ((10 * RANK_RTOL, 6), (0.1 * RANK_RTOL, 5)):
            sv = scale * np.array([1.0, 0.5, 0.2, 0.1, 0.05, ratio])
            assert factor(U @ np.diag(sv) @ V[:6]).rank == rank
