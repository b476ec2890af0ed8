"""The kernel's results: bound structs with named fields, their arrays views of them.

A function that returns several values returns a struct (``kernel.Factor``,
``kernel.CertifiedStep``, ...) whose fields are read-only properties; each array field
is a numpy array made by NumPy's C API over the struct's memory, with the struct as its
base. Checked here: the shapes, dtypes and memory orders, that the arrays are writeable
and independent of other results and of later calls, that an array or a nested struct
keeps its result alive, that an empty result is a proper empty array, that the fields
cannot be assigned, and that the results are freed (a leak of the arrays of 100,000
calls would show as memory).
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
    f = kernel.factor(A)
    np.testing.assert_allclose(f.U @ np.diag(f.sigma) @ f.V.T, A, atol=1e-12)
    for a in (f.U, f.sigma, f.V, f.N):
        assert a.dtype == np.float64 and a.flags.writeable and a.flags.aligned
    assert f.U.flags.f_contiguous and not f.U.flags.owndata  # a view of the kernel's result
    assert f.U.base is f  # the struct owns the memory
    rows = kernel.inequalities(np.array([-1.0, -np.inf]), np.array([2.0, 3.0]),
                               np.array([[1.0, 1.0]]), np.array([0.5]))
    assert (rows.C.shape, rows.e.shape, rows.kind.dtype, rows.index.dtype) == (
        (4, 2), (4,), np.int8, np.int64)
    box = kernel.range_box(np.array([-1.0, 0.5]), np.array([1.0, 2.0]),
                           np.array([0.0, 0.0]), np.array([False, False]))
    assert box.lower.flags.c_contiguous and box.lower.shape == box.upper.shape == (2,)


def test_returned_arrays_are_independent_and_outlive_the_call() -> None:
    lo, hi = np.array([-1.0, -2.0]), np.array([1.0, 2.0])
    first = kernel.range_box(lo, hi, np.zeros(2), np.zeros(2, dtype=bool))
    kept = first.lower.copy(), first.upper.copy()
    first.lower[:] = 99.0  # writing one result touches nothing else
    second = kernel.range_box(lo, hi, np.zeros(2), np.zeros(2, dtype=bool))
    np.testing.assert_array_equal(second.lower, kept[0])
    np.testing.assert_array_equal(first.upper, kept[1])
    lower = first.lower  # a field read again views the same memory
    np.testing.assert_array_equal(lower, [99.0, 99.0])
    del first, second
    gc.collect()
    np.testing.assert_array_equal(lower, [99.0, 99.0])


def test_a_nested_struct_keeps_its_result_alive() -> None:
    A, b = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]), np.ones(2)
    no_rows, no_cost = np.zeros((0, 3)), np.zeros((0, 0))
    step = kernel.solve_certified(A, b, -np.ones(3), np.ones(3), no_rows, np.zeros(0),
                                  np.ones(3), no_cost, no_cost, np.zeros(3), 1e-10, -1, True,
                                  1e-9, 1e-7)
    assert step.code == 0 and step.x.tolist() == [1.0, 1.0, 0.0]
    basis, rows, certificate = step.basis, step.rows, step.certificate
    assert certificate is not None
    del step
    gc.collect()
    assert (basis.rank, basis.N.shape, rows.C.shape) == (2, (3, 1), (6, 3))
    assert certificate.kkt == 1 and certificate.active_upper.tolist() == [True, True, False]
    beyond = kernel.solve_certified(A, 3.0 * b, -np.ones(3), np.ones(3), no_rows,
                                    np.zeros(0), np.ones(3), no_cost, no_cost, np.zeros(3),
                                    1e-10, -1, True, 1e-9, 1e-7)
    assert beyond.code == 1 and beyond.certificate is None  # not an optimum: not certified
    assert beyond.conflicts  # named by their rows


def test_the_fields_are_read_only() -> None:
    f = kernel.factor(np.eye(2))
    with pytest.raises(AttributeError, match=r"setter|can.t set"):
        f.U = np.zeros((2, 2))  # type: ignore[misc]
    np.testing.assert_array_equal(np.abs(f.U), np.eye(2))
    out = kernel.nnls(np.eye(2), np.ones(2), 10)
    with pytest.raises(AttributeError, match=r"setter|can.t set"):
        out.rnorm = 1.0  # type: ignore[misc]
    assert out.rnorm == 0.0


def test_an_empty_result_is_an_empty_array() -> None:
    rows = kernel.inequalities(np.full(3, -np.inf), np.full(3, np.inf), np.zeros((0, 3)),
                               np.zeros(0))
    assert rows.C.shape == (0, 3) and rows.e.shape == (0,)
    assert rows.kind.shape == rows.index.shape == (0,)
    assert rows.C.dtype == np.float64 and rows.kind.dtype == np.int8


@pytest.mark.skipif(sys.platform != "linux", reason="reads the resident set size on Linux")
def test_the_results_are_freed() -> None:
    """100,000 calls returning two arrays of 64 numbers each: 100 MB if they leaked."""
    n = 64
    lo, hi = -np.ones(n), np.ones(n)

    def rss_mb() -> float:
        with open("/proc/self/statm") as f:
            return int(f.read().split()[1]) * resource.getpagesize() / 1e6

    off = np.zeros(n, dtype=bool)
    for _ in range(2000):
        kernel.range_box(lo, hi, lo, off).lower.sum()
    gc.collect()
    before = rss_mb()
    for _ in range(100_000):
        kernel.range_box(lo, hi, lo, off).lower.sum()  # a view keeps the struct until freed
    gc.collect()
    assert rss_mb() - before < 50.0
