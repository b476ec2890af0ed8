"""Frozen dataclasses made unchecked hold what their constructors would have made."""

from __future__ import annotations

import dataclasses
import importlib
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pytest

from dualarm_qp._frozen import made
from dualarm_qp.control import controller as controller_module
from dualarm_qp.solvers import available_solvers, get_solver
from dualarm_qp.solvers import nullspace as nullspace_module
from dualarm_qp.solvers.base import Status, StepSolution
from dualarm_qp.solvers.certify import certify
from dualarm_qp.step import build as build_module
from dualarm_qp.step import problem as problem_module
from dualarm_qp.step.kinematics import both_arms
from tests.control.test_controller_verify import make_controller, stepped

#: The module (the package's ``certify`` is the function of the same name).
certify_module = importlib.import_module("dualarm_qp.solvers.certify")


@dataclass(frozen=True)
class Sample:
    a: float
    b: tuple[int, ...] = ()
    cache: dict[str, int] = field(default_factory=dict, init=False)
    flag: bool = field(default=False, init=False)


def test_made_sets_every_field_and_the_defaults_of_the_others() -> None:
    one = made(Sample, {"a": 1.5, "b": (1, 2)})
    two = made(Sample, {"a": 1.5, "b": (1, 2)})
    assert one == Sample(1.5, (1, 2))
    assert one.cache == {} and one.flag is False
    assert one.cache is not two.cache  # a factory's default is made per object
    with pytest.raises(dataclasses.FrozenInstanceError):
        one.a = 2.0  # type: ignore[misc]


@pytest.mark.parametrize("values", [{"a": 1.0}, {"a": 1.0, "b": (), "c": 3},
                                    {"a": 1.0, "b": (), "cache": {}}])
def test_made_refuses_a_missing_or_an_unknown_field(values: dict[str, object]) -> None:
    with pytest.raises(TypeError, match="every init field"):
        made(Sample, values)


def test_a_field_that_cannot_be_made_is_refused() -> None:
    @dataclass(frozen=True)
    class NoDefault:
        a: float
        b: float = field(init=False)

    with pytest.raises(TypeError, match="no default"):
        made(NoDefault, {"a": 1.0})


def _same(one: object, two: object, where: str) -> None:
    """Every compared field equal, arrays also in dtype and memory order."""
    assert type(one) is type(two), where
    for f in dataclasses.fields(one):  # type: ignore[arg-type]
        if not f.compare:  # caches (what was computed from the fields)
            continue
        a, b = getattr(one, f.name), getattr(two, f.name)
        name = f"{where}.{f.name}"
        if isinstance(a, np.ndarray):
            assert isinstance(b, np.ndarray), name
            assert a.dtype == b.dtype and a.shape == b.shape, name
            assert a.flags.c_contiguous == b.flags.c_contiguous, name
            assert np.array_equal(a, b, equal_nan=True), name
        elif isinstance(a, float) and math.isnan(a):
            assert isinstance(b, float) and math.isnan(b), name
        elif dataclasses.is_dataclass(a):
            _same(a, b, name)
        elif f.name.endswith("_time") or f.name in ("kinematics", "assembly", "solve",
                                                    "verify"):
            assert type(a) is type(b), name  # timings differ from run to run
        elif isinstance(a, dict):
            assert a.keys() == b.keys(), name
        else:
            assert a == b, name


def _run(solver: str, steps: int = 4) -> list[Any]:
    controller, state = make_controller(get_solver(solver))
    return stepped(controller, state, steps)


def _constructed(cls: type, values: dict[str, Any]) -> Any:
    """What :func:`made` stands for: the checking constructor."""
    return cls(**values)


@pytest.mark.parametrize("solver", available_solvers())
def test_the_step_makes_what_the_constructors_make(solver: str,
                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    # The same steps with every object made by its checking constructor: the same
    # values, types, dtypes and memory orders (a constructor that normalised or checked
    # something the unchecked path skips would show here).
    fast = _run(solver)
    for module in (build_module, problem_module, controller_module, nullspace_module,
                   certify_module):
        monkeypatch.setattr(module, "made", _constructed)
    checked = _run(solver)
    for k, (one, two) in enumerate(zip(fast, checked, strict=True)):
        _same(one, two, f"step {k}")
        assert one.build.recovers is two.build.recovers
    for problem in (out.build.problem for out in fast):  # C-ordered float64 throughout
        for name in ("A", "b", "weights", "center", "lower", "upper", "G", "h"):
            array = getattr(problem, name)
            assert array.dtype == np.float64 and array.flags.c_contiguous, name


@pytest.mark.parametrize("solver", ["nullspace", "qp:daqp"])
def test_the_steps_objects_hold_the_right_values(solver: str) -> None:
    # Checked against what computes them independently: the kinematics, the certificate
    # of the answer's x, the split of the applied rates.
    if solver not in available_solvers():
        pytest.skip(f"{solver} is not installed")
    controller, state = make_controller(get_solver(solver))
    task, layout = controller.task, controller.layout
    for _ in range(4):
        out = controller.step(state)
        build, solution, problem = out.build, out.solution, out.build.problem
        arms = both_arms(controller.builder.carry, task.follower, state.q_l, state.q_f,
                         state.sigma, state.sigma_leader, task.trajectory.pose(state.t))
        assert np.array_equal(build.leader_error, arms.leader_error)
        assert np.array_equal(build.closure_error, arms.closure_error)
        assert np.array_equal(build.T_f, arms.T_f) and np.array_equal(build.J_f, arms.J_f)
        assert build.recovers is bool(build.recovering.any())
        assert solution.status is Status.OPTIMAL and solution.scale == 1.0
        again = certify(problem, StepSolution(x=solution.x.copy(), status=Status.OPTIMAL,
                                              solver=solution.solver), controller.tolerance)
        for name in ("status", "objective", "eq_residual", "bound_violation",
                     "row_violation", "active_rows", "message"):
            assert getattr(again, name) == getattr(solution, name), name
        assert np.array_equal(again.active_lower, solution.active_lower)
        assert np.array_equal(again.active_upper, solution.active_upper)
        assert again.build_time == solution.build_time == problem.build_time
        assert out.applied and out.status is Status.OPTIMAL and out.scale == 1.0
        x = np.clip(solution.x, problem.lower, problem.upper)
        assert np.array_equal(out.ql_dot, x[layout.leader])
        assert np.array_equal(out.qf_dot, x[layout.follower])
        assert out.m == x[layout.grasp_follower] and out.m_leader == 0.0
        assert out.times.solve >= 0.0 and out.times.kinematics == build.kinematics_time
        state = state.advanced(out, controller.options.dt)
