"""The arrays the kernel returns: NumPy's own arrays viewing the kernel's results.

Each returned matrix or vector is a numpy array made by NumPy's C API over the result
the kernel moved to the heap, with a capsule that frees it as its base. Checked here:
the shapes, dtypes and memory orders, that the arrays are writeable and independent of
each other and of later calls, that an empty result is a proper empty array, and that
the results are freed (a leak of the arrays of 100,000 calls would show as memory).
"""

from __future__ import annotations

import gc
import resource
import sys

import numpy as np
import pytest

from dualarm_qp._compiled import kernel


def test_returned_arrays_have_their_shapes_dtypes_and_orders() -> None:
    A = np.arange(12.0).reshape(3, 4)
    U, sigma, V, N = kernel.factor(A)
    np.testing.assert_allclose(U @ np.diag(sigma) @ V.T, A, atol=1e-12)
    for a in (U, sigma, V, N):
        assert a.dtype == np.float64 and a.flags.writeable and a.flags.aligned
    assert U.flags.f_contiguous and not U.flags.owndata  # a view of the kernel's result
    C, e, kind, index = kernel.inequalities(np.array([-1.0, -np.inf]), np.array([2.0, 3.0]),
                                            np.array([[1.0, 1.0]]), np.array([0.5]))
    assert (C.shape, e.shape, kind.dtype, index.dtype) == ((4, 2), (4,), np.int8, np.int64)
    lower, upper = kernel.range_box(np.array([-1.0, 0.5]), np.array([1.0, 2.0]),
                                    np.array([0.0, 0.0]), np.array([False, False]))
    assert lower.flags.c_contiguous and lower.shape == upper.shape == (2,)


def test_returned_arrays_are_independent_and_outlive_the_call() -> None:
    lo, hi = np.array([-1.0, -2.0]), np.array([1.0, 2.0])
    first = kernel.range_box(lo, hi, np.zeros(2), np.zeros(2, dtype=bool))
    kept = [a.copy() for a in first]
    first[0][:] = 99.0  # writing one result touches nothing else
    second = kernel.range_box(lo, hi, np.zeros(2), np.zeros(2, dtype=bool))
    np.testing.assert_array_equal(second[0], kept[0])
    np.testing.assert_array_equal(first[1], kept[1])
    lower = first[0]
    del first, second
    gc.collect()
    np.testing.assert_array_equal(lower, [99.0, 99.0])


def test_an_empty_result_is_an_empty_array() -> None:
    C, e, kind, index = kernel.inequalities(np.full(3, -np.inf), np.full(3, np.inf),
                                            np.zeros((0, 3)), np.zeros(0))
    assert C.shape == (0, 3) and e.shape == (0,) and kind.shape == index.shape == (0,)
    assert C.dtype == np.float64 and kind.dtype == np.int8


@pytest.mark.skipif(sys.platform != "linux", reason="reads the resident set size on Linux")
def test_the_results_are_freed() -> None:
    """100,000 calls returning two arrays of 64 numbers each: 100 MB if they leaked."""
    n = 64
    lo, hi = -np.ones(n), np.ones(n)

    def rss_mb() -> float:
        with open("/proc/self/statm") as f:
            return int(f.read().split()[1]) * resource.getpagesize() / 1e6

    for _ in range(2000):
        kernel.range_box(lo, hi, lo, np.zeros(n, dtype=bool))
    gc.collect()
    before = rss_mb()
    for _ in range(100_000):
        kernel.range_box(lo, hi, lo, np.zeros(n, dtype=bool))
    gc.collect()
    assert rss_mb() - before < 50.0
