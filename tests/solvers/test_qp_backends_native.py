"""The native osqp and proxsuite paths: osqp's extension shortcut changes nothing, and
every call is bounded (iteration caps, a Ctrl-C passed on, no banner)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from dualarm_qp.bench.suite import load_suite
from dualarm_qp.solvers import Status, available_solvers, get_solver
from dualarm_qp.solvers.backends import NATIVE, osqp_, shifted
from dualarm_qp.step.problem import StepProblem

SUITE = Path(__file__).resolve().parents[2] / "benchmarks" / "data" / "step_suite.npz"


@pytest.mark.skipif("osqp" not in NATIVE, reason="osqp is not installed")
def test_osqp_extension_path_matches_the_public_api(monkeypatch: pytest.MonkeyPatch) -> None:
    """Same steps in the same order (warm starts, failures and new setups included):
    the same iterates, statuses and iteration counts with and without the shortcut."""
    suite = load_suite(SUITE)
    # QPSolver never hands an empty box (lower > upper) to the backend.
    steps = [p for p in suite.problems[::11] if not (p.lower > p.upper).any()]
    options = get_solver("qp:osqp").options
    fast = NATIVE["osqp"](options)
    fast_out = [fast.solve(p) for p in steps]
    assert fast._ext is not None or fast._solver is None
    monkeypatch.setattr(osqp_, "_osqp_extension", lambda solver: None)
    slow = NATIVE["osqp"](options)
    slow_out = [slow.solve(p) for p in steps]
    assert slow._ext is None
    for a, b in zip(fast_out, slow_out, strict=True):
        assert (a.solved, a.infeasible, a.status, a.iterations) == (
            b.solved, b.infeasible, b.status, b.iterations)
        assert (a.x is None) == (b.x is None)
        if a.x is not None and b.x is not None:
            np.testing.assert_array_equal(a.x, b.x)
    assert sum(a.solved for a in fast_out) > 0 and sum(not a.solved for a in fast_out) > 0


# --- the guards: proxqp's iteration caps, osqp's swallowed SIGINT, HiGHS's banner -------

#: A recorded step (s7 = 1e9) on which proxqp, with the raw cost and its default inner
#: limit (``max_iter_in`` = 1500), stalled for 126,250 iterations (1.9 s); kept as a file
#: of its own since the step suite was regenerated in the configs' units.
PATHOLOGICAL_FILE = Path(__file__).resolve().parent / "data" / "proxqp_pathological_step.npz"


def _pathological_step() -> StepProblem:
    with np.load(PATHOLOGICAL_FILE) as d:
        return StepProblem(A=d["A"], b=d["b"], weights=d["weights"], center=d["center"],
                           lower=d["lower"], upper=d["upper"], n_grasp=int(d["n_grasp"]))


@pytest.mark.skipif("proxqp" not in NATIVE, reason="proxsuite is not installed")
def test_proxsuite_profile_caps_inner_and_outer_iterations() -> None:
    solver = get_solver("qp:proxsuite")
    assert solver.options["max_iter"] * (solver.options["max_iter_in"] + 1) <= 50_000
    problem = _pathological_step()
    sol = solver.solve(problem)
    assert sol.status is Status.OPTIMAL, sol.message
    settings = solver._native._qp.settings  # the options reached the backend
    assert settings.max_iter == solver.options["max_iter"]
    assert settings.max_iter_in == solver.options["max_iter_in"]


@pytest.mark.skipif("proxqp" not in NATIVE, reason="proxsuite is not installed")
def test_proxsuite_pathological_call_returns_within_a_second(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """The raw cost and no preconditioner (the old set-up) stall proxqp on this step;
    the profile's iteration caps end the call well within a second."""
    problem = _pathological_step()
    monkeypatch.setattr(shifted, "cost_weights", lambda w: np.array(w, dtype=float))
    options = {**get_solver("qp:proxsuite").options, "compute_preconditioner": False,
               "eps_primal_inf": 1e-4}
    native = NATIVE["proxqp"](options)
    start = time.perf_counter()
    out = native.solve(problem)
    elapsed = time.perf_counter() - start
    assert not out.solved  # still pathological ...
    assert out.iterations is not None
    assert out.iterations <= options["max_iter"] * (options["max_iter_in"] + 1)
    assert elapsed < 1.0  # ... but bounded


def _endless_osqp() -> osqp_.OSQPNative:
    """An osqp object that never converges (no termination check) for 5 s."""
    return osqp_.OSQPNative({"eps_abs": 1e-300, "eps_rel": 0.0, "check_termination": 0,
                               "polishing": False, "scaling": 0, "max_iter": 10**9,
                               "time_limit": 5.0})


def _interrupt_in(seconds: float) -> threading.Timer:
    timer = threading.Timer(seconds, os.kill, (os.getpid(), signal.SIGINT))
    timer.start()
    return timer


@pytest.mark.sigint  # Python's SIGINT handler
@pytest.mark.skipif("osqp" not in NATIVE, reason="osqp is not installed")
def test_osqp_passes_a_ctrl_c_on_as_keyboard_interrupt() -> None:
    """osqp's own SIGINT handler catches a Ctrl-C during a solve and returns
    "interrupted"; the step is not taken and the KeyboardInterrupt reaches the caller."""
    solver = get_solver("qp:osqp")
    solver.inner._native = _endless_osqp()
    problem = load_suite(SUITE).problems[0]
    timer = _interrupt_in(0.3)
    start = time.perf_counter()
    try:
        with pytest.raises(KeyboardInterrupt):
            solver.solve(problem)
    finally:
        timer.cancel()
    assert time.perf_counter() - start < 3.0  # at the signal, not at the time limit


@pytest.mark.sigint  # the handler installed below is replaced after the test
@pytest.mark.skipif("osqp" not in NATIVE, reason="osqp is not installed")
def test_osqp_interrupted_is_never_a_result() -> None:
    """With a handler that does not raise, the interrupted call is an ERROR with no x,
    and the program's handler still sees the signal."""
    seen: list[int] = []
    signal.signal(signal.SIGINT, lambda signum, frame: seen.append(signum))
    solver = get_solver("qp:osqp")
    solver.inner._native = _endless_osqp()
    problem = load_suite(SUITE).problems[0]
    timer = _interrupt_in(0.3)
    try:
        sol = solver.solve(problem)
    finally:
        timer.cancel()
    assert seen == [signal.SIGINT]
    assert sol.status is Status.ERROR
    assert "interrupt" in sol.extras["backend_status"].lower()
    assert not sol.x.any()


@pytest.mark.skipif("qp:highs" not in available_solvers(), reason="highs is not installed")
@pytest.mark.slow
def test_highs_prints_no_banner() -> None:
    code = ("import numpy as np\n"
            "from dualarm_qp.bench.suite import load_suite\n"
            "from dualarm_qp.solvers import get_solver\n"
            f"p = load_suite({str(SUITE)!r}).problems[0]\n"
            "print(get_solver('qp:highs').solve(p).status.value)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=120, check=True)
    assert out.stdout.strip() == "optimal"
    assert "HiGHS" not in out.stderr
