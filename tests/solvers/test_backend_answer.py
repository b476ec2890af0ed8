"""A backend's answer carries the problem it answers and its own residuals; every backend
module is in the registry."""

from __future__ import annotations

import importlib
import math
import pkgutil

import numpy as np
import pytest

from dualarm_qp.solvers import available_solvers, backends
from dualarm_qp.solvers.backends import BACKENDS, BackendAnswer, solve_with_qpsolvers
from dualarm_qp.solvers.certify import residuals
from dualarm_qp.step.problem import StepProblem


def _problem() -> StepProblem:
    """``x1 + x2 = 1`` on the box ``[0, 0.8]^2`` with one row ``x1 - x2 <= 0.5``, centre (1, 0)."""
    return StepProblem(A=np.array([[1.0, 1.0]]), b=np.array([1.0]), weights=np.ones(2),
                       center=np.array([1.0, 0.0]), lower=np.zeros(2),
                       upper=np.full(2, 0.8), G=np.array([[1.0, -1.0]]),
                       h=np.array([0.5]), n_grasp=1)


def test_answer_gives_its_point_in_the_step_variables() -> None:
    p = _problem()
    answer = BackendAnswer(p, np.array([-0.25, 0.25]), True, False, "solved")
    np.testing.assert_array_equal(answer.x, [0.75, 0.25])
    assert BackendAnswer(p, None, False, True, "infeasible").x is None


def test_answer_residuals_are_those_of_its_point() -> None:
    p = _problem()
    feasible = BackendAnswer(p, np.array([0.7, 0.3]) - p.center, True, False, "solved")
    assert feasible.primal_residual() <= 1e-15
    off_box = BackendAnswer(p, np.array([0.85, 0.15]) - p.center, True, False,
                            "solved")  # 0.05 above the box, and the row's 0.5 by 0.2
    assert off_box.residuals()[1] == pytest.approx(0.2 / math.sqrt(2))  # a unit-norm row
    assert off_box.primal_residual() == pytest.approx(0.2 / math.sqrt(2))
    off_equality = BackendAnswer(p, np.array([0.5, 0.4]) - p.center, True, False, "solved")
    assert off_equality.residuals()[0] == pytest.approx(0.1)
    for y in (None, np.array([np.nan, 0.0])):
        assert BackendAnswer(p, y, False, False, "").residuals() == (math.inf, math.inf)


@pytest.mark.parametrize("key", sorted(BACKENDS))
def test_every_backend_answer_carries_its_residuals(key: str) -> None:
    """Solved through qpsolvers or natively, the answer's residuals are the certificate's."""
    if f"qp:{key}" not in available_solvers():
        pytest.skip(f"{key} not installed")
    backend = BACKENDS[key]
    p = _problem()
    native = backends.NATIVE.get(backend.solver)
    answer = (native(backend.profile).solve(p) if native is not None
              else solve_with_qpsolvers(backend, p, backend.profile))
    assert answer.solved, answer.status
    assert answer.x is not None
    assert answer.residuals() == residuals(p, answer.x)
    assert answer.primal_residual() <= 1e-6


def test_every_backend_module_is_registered() -> None:
    """Adding a backend is one module and one line in the registry: no module is left out."""
    modules = [m.name for m in pkgutil.iter_modules(backends.__path__) if m.name.endswith("_")
               and m.name != "qpsolvers_"]
    found = [importlib.import_module(f"{backends.__name__}.{m}").BACKEND for m in modules]
    assert sorted(b.solver for b in found) == sorted(b.solver for b in BACKENDS.values())
