"""What the certificate reads of an answer, in one compiled call, against numpy.

``kernel.certificate`` gives certify the residuals, the equality's limit, the active
bounds and rows, the objective and (when asked) the KKT test. Each is recomputed here
with numpy from its definition in :mod:`dualarm_qp.solvers.certify`. The problem's own
checks (one compiled pass naming the first bad array) and the smallest singular value
the step reports are checked likewise.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dualarm_qp._compiled import kernel
from dualarm_qp.errors import NonFiniteError, ShapeError
from dualarm_qp.solvers import Status, StepSolution, get_solver
from dualarm_qp.solvers._affine import cost_arrays, problem_basis
from dualarm_qp.solvers.certify import ACTIVE_TOL, certify, kkt_holds
from dualarm_qp.step.build import smallest_singular_value
from dualarm_qp.step.problem import StepProblem

seeds = st.integers(min_value=0, max_value=2**32 - 1)


def problem_and_points(seed):
    """A random step with rows, and points on and off its limits."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(3, 10))
    m = int(rng.integers(0, n))
    A = rng.normal(size=(m, n))
    x_in = rng.uniform(-0.5, 0.5, n)
    p = int(rng.integers(0, 4))
    G = rng.normal(size=(p, n))
    dense = bool(rng.integers(2))
    if dense:
        B = rng.normal(size=(n, n))
        weights = B @ B.T + n * np.eye(n)
    else:
        weights = 10.0 ** rng.uniform(-1, 3, n)
    problem = StepProblem(A=A, b=A @ x_in, weights=weights, center=rng.normal(0, 2, n),
                          lower=-rng.uniform(0.6, 2.0, n), upper=rng.uniform(0.6, 2.0, n),
                          G=G, h=G @ x_in + rng.uniform(0.0, 0.5, p))
    solved = get_solver("nullspace").solve(problem).x
    points = [solved, x_in, rng.normal(0, 2, n)]
    if n:  # exactly on one bound
        x = x_in.copy()
        x[0] = problem.upper[0]
        points.append(x)
    return problem, points


@settings(max_examples=120, deadline=None)
@given(seeds, st.booleans())
def test_the_compiled_certificate_equals_its_definitions(seed, bounds):
    problem, points = problem_and_points(seed)
    f = problem_basis(problem)
    ineq = problem.inequalities()
    w_diag, w_full, root_full = cost_arrays(problem)
    W = problem.weight_matrix()
    for x in points:
        c = kernel.certificate(
            problem.A, problem.b, problem.lower, problem.upper, problem.G, problem.h,
            f, ineq.C, ineq.e, ineq.kind, ineq.index, w_diag, w_full, root_full,
            problem.center, x, bounds, 1e-7, 1e-7, True)
        assert c.finite
        eq, box, rows, limit = c.eq, c.box, c.row, c.eq_limit
        want_eq = np.abs(problem.A @ x - problem.b).max(initial=0.0)
        want_box = max(0.0, float(np.max(np.r_[problem.lower - x, x - problem.upper])))
        norms = np.linalg.norm(problem.G, axis=1)
        gaps = (problem.G @ x - problem.h) / np.where(norms > 0, norms, 1.0)
        want_rows = max(0.0, float(gaps.max(initial=0.0)))
        assert eq == pytest.approx(want_eq, rel=1e-12, abs=1e-14)
        assert box == pytest.approx(want_box, rel=1e-12, abs=1e-15)
        assert rows == pytest.approx(want_rows, rel=1e-12, abs=1e-14)
        assert limit == 1e-7 * max(1.0, float(np.abs(problem.b).max(initial=0.0)))
        d = x - problem.center
        assert c.objective == pytest.approx(float(d @ W @ d), rel=1e-12)
        assert c.active_lower.dtype == c.active_upper.dtype == np.bool_
        np.testing.assert_array_equal(c.active_lower, problem.lower - x >= -ACTIVE_TOL)
        np.testing.assert_array_equal(c.active_upper, x - problem.upper >= -ACTIVE_TOL)
        on = (ineq.kind == 0) & (ineq.C @ x - ineq.e >= -ACTIVE_TOL)
        # Named by their rows of G: the rows of C of kind 0 map to G through the index.
        assert c.active_rows == ineq.index[on].tolist()
        assert all(gaps[j] >= -ACTIVE_TOL for j in c.active_rows)
        meets = eq <= limit and max(box, rows) <= 1e-7
        assert c.kkt == (int(kkt_holds(problem, x, bounds=bounds)) if meets else -1)


def test_the_kkt_test_is_not_run_unless_asked():
    problem, points = problem_and_points(7)
    ineq = problem.inequalities()
    out = kernel.certificate(
        problem.A, problem.b, problem.lower, problem.upper, problem.G, problem.h,
        problem_basis(problem), ineq.C, ineq.e, ineq.kind, ineq.index,
        *cost_arrays(problem),
        problem.center, points[0], True, 1e-7, 1e-7, False)
    assert out.kkt == -1


@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_a_non_finite_answer_is_an_error_and_a_float32_one_is_read(bad):
    problem, points = problem_and_points(11)
    x = points[0].copy()
    x[-1] = bad
    out = certify(problem, StepSolution(x=x, status=Status.OPTIMAL))
    assert out.status is Status.ERROR and not out.x.any()
    single = certify(problem, StepSolution(x=points[0].astype(np.float32),
                                           status=Status.FEASIBLE))
    assert single.status.usable and single.x.dtype == np.float64


@pytest.mark.parametrize("name", ["A", "b", "weights", "center", "G", "lower", "upper", "h"])
def test_the_problem_names_the_first_array_holding_a_value_it_may_not(name):
    problem, _ = problem_and_points(13)
    fields = {k: getattr(problem, k).copy() for k in
              ("A", "b", "weights", "center", "G", "lower", "upper", "h")}
    if name in ("G", "h"):
        fields["G"], fields["h"] = np.ones((1, problem.n)), np.ones(1)
    if fields[name].size == 0:
        pytest.skip("no equality rows in this draw")
    fields[name].flat[0] = np.nan
    with pytest.raises(NonFiniteError, match=f"^{name} contains"):
        StepProblem(**fields)
    if name in ("lower", "upper", "h"):  # infinite: no limit, allowed
        fields[name].flat[0] = np.inf if name != "lower" else -np.inf
        StepProblem(**fields)
    else:
        fields[name].flat[0] = np.inf
        with pytest.raises(NonFiniteError, match=f"^{name} contains"):
            StepProblem(**fields)


def test_a_scaled_problem_is_checked_where_it_changed():
    problem, points = problem_and_points(17)
    assert problem.m  # seed chosen with equality rows
    out = problem.scaled(0.5, x_prev=points[1])
    np.testing.assert_array_equal(out.b, 0.5 * problem.b)
    assert out.x_prev is not None and out.A is problem.A and problem.b is not out.b
    with pytest.raises(NonFiniteError, match="scale"):
        problem.scaled(np.inf)
    big = StepProblem(A=np.eye(2), b=np.array([10.0, 1.0]), weights=np.ones(2),
                      center=np.zeros(2), lower=-np.ones(2), upper=np.ones(2))
    with pytest.raises(NonFiniteError, match=r"^b \(scaled\)"):  # 1e308 * 10 overflows
        big.scaled(1e308)
    with pytest.raises(ShapeError, match="x_prev"):
        problem.scaled(0.5, x_prev=np.zeros(problem.n + 1))


@settings(max_examples=100, deadline=None)
@given(seeds, st.integers(min_value=0, max_value=3))
def test_the_smallest_singular_value_equals_numpys(seed, drop):
    rng = np.random.default_rng(seed)
    J = rng.normal(size=(6, int(rng.integers(6, 8))))
    if drop:  # a near-singular Jacobian: singular values down to 1e-9 (perturbed)
        U, s, Vt = np.linalg.svd(J, full_matrices=False)
        s[-drop:] = 10.0 ** -rng.uniform(3, 9, drop)
        J = (U * s) @ Vt
    want = np.linalg.svd(J, compute_uv=False)[-1]
    assert smallest_singular_value(J) == pytest.approx(want, rel=1e-9, abs=1e-14)
    assert smallest_singular_value(J[:, :5]) == 0.0  # fewer joints than task rows


@settings(max_examples=300, deadline=None)
@given(seeds, st.integers(min_value=1, max_value=6), st.integers(min_value=0, max_value=3),
       st.sampled_from([1e-300, 1e-150, 1e-3, 1.0, 1e150, 1e300]),
       st.sampled_from(["random", "dependent", "zero row", "graded"]))
def test_the_smallest_singular_value_holds_at_any_scale_and_rank(seed, m, extra, scale, kind):
    # The kernel's one-sided Jacobi against numpy's SVD (LAPACK), within a few rounding
    # errors of the largest singular value, from 1e-300 to 1e300 (scaled exactly inside).
    rng = np.random.default_rng(seed)
    J0 = rng.normal(size=(m, m + extra))
    if kind == "dependent" and m > 1:
        J0[0] = rng.normal(size=m - 1) @ J0[1:]
    elif kind == "zero row":
        J0[int(rng.integers(m))] = 0.0
    elif kind == "graded":
        J0 *= (10.0 ** -np.arange(m))[:, None]
    s = np.linalg.svd(J0, compute_uv=False)
    got = smallest_singular_value(J0 * scale)
    assert abs(got / scale - s[-1]) <= 8 * np.finfo(float).eps * s[0]
    if s[-1] > 1e-6 * s[0]:  # well conditioned: to a relative error of cond(J) * eps
        assert got / scale == pytest.approx(s[-1], rel=64 * np.finfo(float).eps * s[0] / s[-1])


def test_rows_of_very_different_sizes_are_orthogonal_when_their_product_underflows():
    # The squared norms' product underflows to 0 here (a tolerance of 0 would rotate the
    # pair for ever): the test takes the norms' product, and the answer is LAPACK's.
    J = np.array([[-7.82e-76, -2.57e-76, 8.14e-78], [-2.76e-96, 1.29e-95, 1.01e-95]])
    want = np.linalg.svd(J, compute_uv=False)
    assert abs(smallest_singular_value(J) - want[-1]) <= 4 * np.finfo(float).eps * want[-1]
    graded = np.random.default_rng(1).normal(size=(6, 7)) * 1e-75
    graded *= (10.0 ** -np.arange(0, 48, 8))[:, None]
    want = np.linalg.svd(graded, compute_uv=False)
    assert abs(smallest_singular_value(graded) - want[-1]) <= 8 * np.finfo(float).eps * want[0]


def test_the_smallest_singular_value_of_no_rows_and_of_nan():
    assert smallest_singular_value(np.zeros((0, 3))) == np.inf
    J = np.eye(6)
    J[2, 2] = np.nan
    assert np.isnan(smallest_singular_value(J))


def test_a_broadcast_view_is_read_as_the_array_it_shows():
    """A problem given broadcast views (zero strides) solves as the plain arrays do."""
    n = 7
    row, other = np.linspace(-1.0, 1.0, n), np.linspace(0.5, -0.3, n)
    fields = dict(b=np.ones(2), center=np.zeros(n), lower=-np.ones(n), upper=np.ones(n),
                  h=np.full(3, 0.2))
    plain = StepProblem(A=np.tile(row, (2, 1)), weights=np.full(n, 2.0),
                        G=np.tile(other, (3, 1)), **fields)
    views = StepProblem(A=np.broadcast_to(row, (2, n)), weights=np.broadcast_to(2.0, (n,)),
                        G=np.broadcast_to(other, (3, n)), **fields)
    assert views.A.strides[0] != 0 and views.G.strides[0] != 0  # plain copies, once
    solver = get_solver("nullspace")
    a, b = solver.solve(plain), solver.solve(views)
    assert a.status is b.status and a.status.usable
    np.testing.assert_array_equal(a.x, b.x)


def test_the_kernel_refuses_arguments_of_inconsistent_sizes():
    problem, points = problem_and_points(29)
    ineq = problem.inequalities()
    with pytest.raises(ValueError, match="inconsistent sizes"):
        kernel.certificate(
            problem.A, problem.b, problem.lower, problem.upper, problem.G, problem.h,
            problem_basis(problem), ineq.C, ineq.e, ineq.kind, ineq.index,
            *cost_arrays(problem), problem.center, np.zeros(problem.n + 1), True, 1e-7,
            1e-7, True)
    other = kernel.basis(np.ones((problem.m + 1, problem.n)))  # of an A with one more row
    with pytest.raises(ValueError, match="basis"):
        kernel.kkt_holds(problem.A, problem.b, other, ineq.C, ineq.e,
                         *cost_arrays(problem), problem.center, points[0], True)
    with pytest.raises(ValueError, match="basis"):  # the KKT test without a basis
        kernel.certificate(
            problem.A, problem.b, problem.lower, problem.upper, problem.G, problem.h, None,
            ineq.C, ineq.e, ineq.kind, ineq.index, *cost_arrays(problem), problem.center,
            points[0], True, 1e-7, 1e-7, True)


def test_the_kernel_refuses_a_general_row_named_by_no_row_of_g() -> None:
    """The certificate names its active general rows by their rows of ``G`` (the rows'
    index): an index outside ``G`` is refused, never read as another row's name."""
    n = 3
    problem = StepProblem(A=np.zeros((0, n)), b=np.zeros(0), weights=np.ones(n),
                          center=np.zeros(n), lower=np.full(n, -1.0), upper=np.full(n, 1.0),
                          G=np.eye(2, n), h=np.array([0.5, 0.5]), n_grasp=0)
    ineq = problem.inequalities()
    general = np.flatnonzero(ineq.kind == 0)
    assert general.size == 2
    for wrong in (-1, problem.p):
        bad = ineq.index.copy()
        bad[general[0]] = wrong
        with pytest.raises(ValueError, match="row of G"):
            kernel.certificate(
                problem.A, problem.b, problem.lower, problem.upper, problem.G, problem.h,
                None, ineq.C, ineq.e, ineq.kind, bad, *cost_arrays(problem), problem.center,
                np.zeros(n), True, 1e-7, 1e-7, False)
