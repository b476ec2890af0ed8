"""Frozen dataclasses made unchecked hold what their constructors would have made."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np
import pytest

from dualarm_qp._frozen import made
from dualarm_qp.solvers import available_solvers, get_solver
from tests.control.test_controller_verify import make_controller


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


def _same(one: object, two: object) -> None:
    """Every field of two dataclass instances equal (arrays element by element)."""
    for f in dataclasses.fields(one):  # type: ignore[arg-type]
        if not f.compare:  # caches (what was computed from the fields)
            continue
        a, b = getattr(one, f.name), getattr(two, f.name)
        if isinstance(a, np.ndarray):
            assert np.array_equal(a, b, equal_nan=True), f.name
        elif isinstance(a, float) and math.isnan(a):
            assert math.isnan(b), f.name
        elif dataclasses.is_dataclass(a):
            _same(a, b)
        else:
            assert a == b, f.name


@pytest.mark.parametrize("solver", available_solvers())
def test_a_steps_objects_pass_their_constructors_checks(solver: str) -> None:
    # The step makes its output, build, problem and (exact solver) solution unchecked:
    # made again through each class's checking constructor, they are the same.
    controller, state = make_controller(get_solver(solver))
    for _ in range(3):
        out = controller.step(state)
        for obj in (out, out.build, out.build.problem, out.solution):
            _same(obj, dataclasses.replace(obj))
        state = state.advanced(out, controller.options.dt)
