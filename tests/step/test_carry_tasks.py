"""The equality block the kernel assembles (Eqs. 14 and 25-27) against numpy's rows."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dualarm_qp._compiled import kernel


def reference(J_o, J_t, J_f, n_l, twist, e_l, e_c, scale, K_l, K, exact):
    n_f = J_f.shape[1]
    k = J_o.shape[1] - n_l
    n = n_l + n_f + k
    leader, follower, grasps = slice(0, n_l), slice(n_l, n_l + n_f), slice(n_l + n_f, n)
    A = np.zeros((12, n))
    A[:6, leader] = J_o[:, :n_l]
    A[:6, grasps] = J_o[:, n_l:]
    A[6:, leader] = -J_t[:, :n_l]
    A[6:, follower] = J_f
    A[6:, grasps] = -J_t[:, n_l:]
    if not exact:
        A[9:, n_l + n_f] = 0.0
    b = np.r_[scale * twist + K_l * e_l, K * e_c]
    return A, b


@settings(max_examples=60, deadline=None)
@given(n_l=st.integers(1, 7), n_f=st.integers(1, 7), k=st.integers(1, 2),
       exact=st.booleans(), seed=st.integers(0, 2**32 - 1))
def test_kernel_rows_equal_numpy_rows(n_l: int, n_f: int, k: int, exact: bool, seed: int
                                      ) -> None:
    rng = np.random.default_rng(seed)
    J_o, J_t = rng.normal(size=(6, n_l + k)), rng.normal(size=(6, n_l + k))
    J_f = rng.normal(size=(6, n_f))
    twist, e_l, e_c = rng.normal(size=6), rng.normal(size=6), rng.normal(size=6)
    scale, K_l, K = rng.uniform(0, 1), rng.uniform(0, 10), rng.uniform(0, 10)
    A = np.empty((12, n_l + n_f + k))
    b = np.empty(12)
    assert kernel.carry_equality(n_l, J_o, J_t, J_f, twist, e_l, e_c, scale, K_l, K, exact, A, b)
    A_ref, b_ref = reference(J_o, J_t, J_f, n_l, twist, e_l, e_c, scale, K_l, K, exact)
    np.testing.assert_array_equal(A, A_ref)
    np.testing.assert_array_equal(b, b_ref)


def test_non_finite_rows_are_reported() -> None:
    J = np.ones((6, 7))
    A, b = np.empty((12, 13)), np.empty(12)
    twist = np.zeros(6)
    assert kernel.carry_equality(6, J, J, np.ones((6, 6)), twist, twist, twist, 1.0, 1.0, 1.0,
                                 False, A, b)
    twist[2] = np.nan
    assert not kernel.carry_equality(6, J, J, np.ones((6, 6)), twist, twist, np.zeros(6), 1.0,
                                     1.0, 1.0, False, A, b)
    with pytest.raises(ValueError, match="carry_equality"):
        kernel.carry_equality(6, J, J, np.ones((6, 6)), twist, twist, twist, 1.0, 1.0, 1.0,
                              False, np.empty((12, 12)), b)
