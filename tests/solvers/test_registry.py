"""Registry look-ups, error messages, options and verification of claimed solutions."""

from __future__ import annotations

import numpy as np
import pytest
from solver_cases import random_problem

from dualarm_qp.errors import InvalidInputError, SolverNotFoundError
from dualarm_qp.solvers import (
    Status,
    StepSolution,
    StepSolver,
    available_solvers,
    certify,
    get_solver,
    list_solvers,
    register,
    solver_info,
)
from dualarm_qp.solvers import registry as registry_module


def test_every_solver_module_is_registered() -> None:
    names = {info.name for info in list_solvers()}
    assert {"reference", "fixed_grasp", "nullspace", "sns", "qp:osqp", "qp:proxsuite",
            "qp:daqp", "qp:clarabel", "qp:piqp", "qp:highs", "qp:quadprog"} <= names
    for info in list_solvers():
        if info.name.startswith("qp:"):
            assert info.extra is not None


@pytest.mark.parametrize("name", available_solvers())
def test_available_solvers_follow_the_protocol(name: str) -> None:
    solver = get_solver(name)
    assert isinstance(solver, StepSolver)
    assert solver.name == name


def test_unknown_name_lists_the_available_solvers() -> None:
    with pytest.raises(SolverNotFoundError) as info:
        get_solver("qp:nonexistent")
    assert "unknown solver 'qp:nonexistent'" in str(info.value)
    assert "nullspace" in str(info.value)
    assert "nullspace" in info.value.available


def test_unavailable_solver_names_its_pip_extra(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(registry_module, "_REGISTRY", dict(registry_module._REGISTRY))
    register("qp:fake", lambda **_: get_solver("nullspace"), description="fake",
             available=False, extra="fakebackend")
    assert "qp:fake" not in available_solvers()
    with pytest.raises(SolverNotFoundError) as info:
        get_solver("qp:fake")
    assert "pip install 'dualarm-qp[fakebackend]'" in str(info.value)
    assert info.value.extra == "fakebackend"


def test_availability_given_as_a_function_is_asked_once_and_only_when_read(
        monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(registry_module, "_REGISTRY", dict(registry_module._REGISTRY))
    asked: list[str] = []

    def probe(name: str, answer: bool):
        return lambda: asked.append(name) or answer

    register("qp:lazy_yes", lambda **_: get_solver("nullspace"), description="lazy",
             available=probe("yes", True))
    register("qp:lazy_no", lambda **_: get_solver("nullspace"), description="lazy",
             available=probe("no", False), extra="fakebackend")
    assert get_solver("nullspace").name == "nullspace"
    assert asked == []  # another solver's entry does not ask
    assert solver_info("qp:lazy_yes").available
    assert asked == ["yes"]
    names = available_solvers()
    assert "qp:lazy_yes" in names and "qp:lazy_no" not in names
    assert sorted(asked) == ["no", "yes"]
    available_solvers()
    solver_info("qp:lazy_yes")
    assert sorted(asked) == ["no", "yes"]  # each answer is kept
    with pytest.raises(SolverNotFoundError):
        get_solver("qp:lazy_no")


def test_proxqp_alias() -> None:
    if "qp:proxsuite" not in available_solvers():
        pytest.skip("proxsuite not installed")
    assert get_solver("qp:proxqp").name == "qp:proxsuite"


def test_backend_options_override_the_profile() -> None:
    if "qp:osqp" not in available_solvers():
        pytest.skip("osqp not installed")
    solver = get_solver("qp:osqp", eps_abs=1e-5, max_iter=7)
    assert solver.options["eps_abs"] == 1e-5  # type: ignore[attr-defined]
    assert solver.options["max_iter"] == 7  # type: ignore[attr-defined]
    assert solver.options["polishing"] is True  # type: ignore[attr-defined]


@pytest.mark.parametrize("name", [n for n in ("qp:daqp", "qp:osqp", "qp:proxsuite")
                                  if n in available_solvers()])
def test_bad_backend_option_is_refused_when_the_solver_is_built(name: str) -> None:
    """A backend that knows its options refuses a wrong one at once, naming it."""
    with pytest.raises(InvalidInputError, match="no_such_option"):
        get_solver(name, no_such_option=1)
    # A good option is accepted and used.
    key = "iter_limit" if name == "qp:daqp" else "max_iter"
    assert get_solver(name, **{key: 77}).options[key] == 77  # type: ignore[attr-defined]


def test_bad_solver_option_is_invalid_input() -> None:
    with pytest.raises(InvalidInputError, match="nullspace"):
        get_solver("nullspace", no_such_option=1)


def test_certify_downgrades_a_false_claim() -> None:
    problem = random_problem(np.random.default_rng(1))
    good = get_solver("nullspace").solve(problem)
    off_task = certify(problem, StepSolution(x=good.x + 0.1, status=Status.OPTIMAL))
    assert off_task.status is Status.VIOLATION
    assert "equality residual" in off_task.message
    out_of_box = problem.upper + 1.0
    fake = StepSolution(x=out_of_box, status=Status.OPTIMAL)
    assert certify(problem, fake).status is Status.VIOLATION
    nan = certify(problem, StepSolution(x=np.full(7, np.nan), status=Status.OPTIMAL))
    assert nan.status is Status.ERROR
    assert np.array_equal(nan.x, np.zeros(7))
    honest = certify(problem, good)
    assert honest.status is Status.OPTIMAL
    assert honest.objective == pytest.approx(problem.objective(good.x))


@pytest.mark.parametrize("name", ["nullspace", "reference"])
def test_a_certified_solver_pickles_and_copies(name: str) -> None:
    """The wrapper forwards attributes to its solver, never its own: no recursion."""
    import copy
    import pickle

    solver = get_solver(name)
    problem = random_problem(np.random.default_rng(3))
    expected = solver.solve(problem)
    for other in (pickle.loads(pickle.dumps(solver)), copy.deepcopy(solver), copy.copy(solver)):
        assert other.name == solver.name and other.inner is not None
        got = other.solve(problem)
        assert got.status is expected.status
        np.testing.assert_array_equal(got.x, expected.x)
    with pytest.raises(AttributeError):
        solver.__no_such_attribute__  # noqa: B018
