"""The exact solver's basis of ``A``: a QR path where it proves full row rank, else the SVD.

:func:`~dualarm_qp.solvers._affine.null_basis` must take the rank decision that
:func:`~dualarm_qp.solvers._affine.factor` (the SVD at ``RANK_RTOL``) takes, and give
the same pseudo-inverse and the same null space, on random matrices, on matrices whose
smallest singular value is put near the tolerance on either side (perturbed), on
rank-deficient ones and on shapes with no rows or more rows than columns.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dualarm_qp.solvers._affine import RANK_RTOL, factor, null_basis

seeds = st.integers(min_value=0, max_value=2**32 - 1)


def with_singular_values(rng, m, n, sv):
    """An m x n matrix with the singular values ``sv`` (random singular vectors)."""
    U, _ = np.linalg.qr(rng.normal(size=(m, m)))
    V, _ = np.linalg.qr(rng.normal(size=(n, n)))
    S = np.zeros((m, n))
    S[np.arange(len(sv)), np.arange(len(sv))] = sv
    return U @ S @ V.T


def assert_same(A):
    """The basis equals the SVD's: rank, pseudo-inverse and null-space projector."""
    f, g = factor(A), null_basis(A)
    assert g.rank == f.rank and g.nullity == f.nullity
    n = A.shape[1]
    pinv = f.V @ np.diag(1.0 / f.sigma) @ f.U.T if f.rank else np.zeros((n, A.shape[0]))
    scale = max(1.0, float(np.abs(pinv).max(initial=0.0)))
    # Both are backward stable: they differ by rounding times the condition number.
    cond = float(f.sigma[0] / f.sigma[-1]) if f.rank else 1.0
    tol = max(1e-10, 1e-14 * cond)
    np.testing.assert_allclose(g.P, pinv, rtol=0.0, atol=tol * scale)
    np.testing.assert_allclose(g.N @ g.N.T, f.N @ f.N.T, rtol=0.0, atol=tol)
    np.testing.assert_allclose(g.N.T @ g.N, np.eye(g.nullity), rtol=0.0, atol=1e-12)
    if g.nullity and A.size:  # what the cut-off drops, and rounding
        dropped = RANK_RTOL * g.sigma_max * np.sqrt(g.nullity)
        assert np.abs(A @ g.N).max() <= dropped + 1e-12 * max(1.0, np.abs(A).max())
    return g


@settings(max_examples=150, deadline=None)
@given(seeds)
def test_a_well_conditioned_matrix_takes_the_qr_path_with_the_svds_answer(seed):
    rng = np.random.default_rng(seed)
    m = int(rng.integers(1, 14))
    n = m + int(rng.integers(0, 4))
    sv = np.sort(10.0 ** rng.uniform(-4, 2, m))[::-1]
    g = assert_same(with_singular_values(rng, m, n, sv))
    assert g.qr and g.rank == m


@settings(max_examples=150, deadline=None)
@given(seeds, st.sampled_from([1e-3, 1e-1, 10.0, 1e3]), st.floats(1e-12, 1e-6))
def test_near_the_tolerance_the_decision_is_the_svds(seed, size, ratio):
    """sigma_min / sigma_max from 1e-12 to 1e-6 (about RANK_RTOL = 1e-9), perturbed."""
    rng = np.random.default_rng(seed)
    m = int(rng.integers(2, 13))
    n = m + int(rng.integers(0, 3))
    sv = np.sort(rng.uniform(0.5, 2.0, m))[::-1] * size
    sv[-1] = ratio * sv[0]
    A = with_singular_values(rng, m, n, sv)
    A = A + rng.normal(size=A.shape) * 1e-15 * np.abs(A).max()
    g = assert_same(A)
    if g.qr:  # the QR path only where it proved full row rank
        assert np.linalg.svd(A, compute_uv=False)[-1] > RANK_RTOL * sv[0]


@pytest.mark.parametrize("shape", [(0, 5), (6, 6), (5, 3), (7, 7)])
def test_rank_deficient_empty_and_tall_matrices_take_the_svd(shape):
    rng = np.random.default_rng(1)
    m, n = shape
    A = rng.normal(size=shape)
    if m == n:  # a repeated row
        A[-1] = A[0]
    g = assert_same(A)
    assert not g.qr
    if m == 0:
        assert g.rank == 0 and g.nullity == n
