"""The native osqp path: calling osqp's extension solver directly changes nothing."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from dualarm_qp.bench.suite import load_suite
from dualarm_qp.solvers import _native, get_solver

SUITE = Path(__file__).resolve().parents[2] / "benchmarks" / "data" / "step_suite.npz"


@pytest.mark.skipif("osqp" not in _native.NATIVE, reason="osqp is not installed")
def test_osqp_extension_path_matches_the_public_api(monkeypatch: pytest.MonkeyPatch) -> None:
    """Same steps in the same order (warm starts, failures and new setups included):
    the same iterates, statuses and iteration counts with and without the shortcut."""
    suite = load_suite(SUITE)
    # QPSolver never hands an empty box (lower > upper) to the backend.
    steps = [p for p in suite.problems[::11] if not (p.lower > p.upper).any()]
    options = get_solver("qp:osqp").options
    fast = _native.NATIVE["osqp"](options)
    fast_out = [fast.solve(p) for p in steps]
    assert fast._ext is not None or fast._solver is None
    monkeypatch.setattr(_native, "_osqp_extension", lambda solver: None)
    slow = _native.NATIVE["osqp"](options)
    slow_out = [slow.solve(p) for p in steps]
    assert slow._ext is None
    for a, b in zip(fast_out, slow_out, strict=True):
        assert (a.solved, a.infeasible, a.status, a.iterations) == (
            b.solved, b.infeasible, b.status, b.iterations)
        assert (a.x is None) == (b.x is None)
        if a.x is not None and b.x is not None:
            np.testing.assert_array_equal(a.x, b.x)
    assert sum(a.solved for a in fast_out) > 0 and sum(not a.solved for a in fast_out) > 0
