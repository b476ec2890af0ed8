"""The limits' rows: checked once, as the builder stacks them, and the problem assembled.

The builder checks each limit's rows where it stacks them (shape, numbers, NaN and
infinity, naming the limit) and assembles the step problem from its checked parts
without a second check (:meth:`StepProblem.assembled`). The assembled problem must be
the one the checking constructor builds from the same parts.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from test_step_builder import make_task, options

from dualarm_qp.errors import InvalidInputError, NonFiniteError, ShapeError
from dualarm_qp.experiments import build_experiment, load_config
from dualarm_qp.step.build import StepBuilder
from dualarm_qp.step.parts import Constraint
from dualarm_qp.step.problem import StepProblem
from dualarm_qp.step.state import DualArmState
from dualarm_qp.task.surfaces import PlaneBar

CONFIGS = Path(__file__).resolve().parents[2] / "configs"


class _Rows:
    """A user's limit that gives chosen rows."""

    gives_rows = True

    def __init__(self, name, rows, names=()):
        self.name, self._rows, self._names = name, rows, names

    def constraint(self, ctx):
        G, h = self._rows(ctx.layout.n)
        return Constraint(G=G, h=h, row_names=self._names)


def _build(*limits):
    rng = np.random.default_rng(3)
    task, q_l, q_f, sigma = make_task(rng, PlaneBar())
    builder = StepBuilder(task, options(), limits=limits)
    return builder.build(DualArmState(0.0, q_l, q_f, sigma)).problem


def _good(n):
    return np.ones((2, n)), np.array([1.0, np.inf])


@pytest.mark.parametrize(("rows", "error", "words"), [
    (lambda n: (np.ones((2, n + 1)), np.zeros(2)), ShapeError, "rows of the limit 'bad'"),
    (lambda n: (np.ones((2, n)), np.zeros(3)), ShapeError, "rows of the limit 'bad'"),
    (lambda n: (np.ones((2, n)), np.zeros((2, 1))), ShapeError, "rows of the limit 'bad'"),
    (lambda n: (np.full((1, n), np.nan), np.zeros(1)), NonFiniteError,
     "rows of the limit 'bad'"),
    (lambda n: (np.full((1, n), np.inf), np.zeros(1)), NonFiniteError,
     "rows of the limit 'bad'"),
    (lambda n: (np.ones((1, n)), np.array([np.nan])), NonFiniteError,
     "rows of the limit 'bad'"),
    (lambda n: (np.full((1, n), "a"), np.zeros(1)), InvalidInputError,
     "rows of the limit 'bad' are not numbers"),
])
def test_a_limits_broken_rows_are_a_clear_error_naming_it(rows, error, words):
    with pytest.raises(error, match=words):
        _build(_Rows("good", _good), _Rows("bad", rows))


def test_row_names_of_the_wrong_length_are_refused():
    with pytest.raises(ShapeError, match="row names of the limit 'named'"):
        _build(_Rows("named", _good, names=("only one",)))


def test_two_limits_whose_wrong_shapes_cancel_are_refused():
    # 2 rows with 3 right-hand sides, then 2 rows with 1: the totals match (4, 4).
    with pytest.raises(ShapeError, match="rows of the limit 'a'"):
        _build(_Rows("a", lambda n: (np.ones((2, n)), np.zeros(3))),
               _Rows("b", lambda n: (np.ones((2, n)), np.zeros(1))))


@pytest.mark.parametrize(("x_prev", "error"), [(np.zeros(3), ShapeError),
                                               (np.zeros((13, 1)), ShapeError),
                                               (["a"] * 13, InvalidInputError)])
def test_a_bad_warm_start_is_a_clear_error(x_prev, error):
    rng = np.random.default_rng(3)
    task, q_l, q_f, sigma = make_task(rng, PlaneBar())
    builder = StepBuilder(task, options())
    with pytest.raises(error, match="x_prev"):
        builder.build(DualArmState(0.0, q_l, q_f, sigma), x_prev=x_prev)


def test_a_warm_start_of_ints_is_taken_as_floats():
    rng = np.random.default_rng(3)
    task, q_l, q_f, sigma = make_task(rng, PlaneBar())
    builder = StepBuilder(task, options())
    n = builder.n
    p = builder.build(DualArmState(0.0, q_l, q_f, sigma), x_prev=[0] * n).problem
    assert p.x_prev is not None and p.x_prev.dtype == np.float64 and p.x_prev.shape == (n,)


def test_rows_of_integers_and_lists_are_taken_as_floats():
    p = _build(_Rows("ints", lambda n: ([[1] * n], [2])), _Rows("good", _good))
    assert p.G.dtype == np.float64 and p.G.flags.c_contiguous and p.G.shape[0] == 3
    assert p.h.tolist() == [2.0, 1.0, np.inf]
    assert p.row_names == ("ints 1", "good 1", "good 2")


def checked_copy(problem: StepProblem) -> StepProblem:
    """Copies of the same parts through the checking constructor (Fortran-ordered, so
    that the constructor makes its own C-ordered float arrays)."""
    parts = {f.name: (np.asfortranarray(np.array(v)) if isinstance(v, np.ndarray) else v)
             for f in dataclasses.fields(StepProblem) if f.init
             for v in (getattr(problem, f.name),)}
    return StepProblem(**parts)


@pytest.mark.parametrize("name", ["puma_beam_limits", "ur5_pair_collision",
                                  "both_sliding_bar", "ur5_pair_heavy_bar"])
def test_the_assembled_problem_is_the_checked_one(name):
    path = CONFIGS / f"{name}.yaml"
    exp = build_experiment(load_config(path), str(path))
    ctrl = exp.controller()
    ctrl.step(exp.initial)
    out = ctrl.step(exp.initial)  # the second step has a warm start
    problem = out.build.problem
    assert problem.x_prev is not None
    ref = checked_copy(problem)
    for f in dataclasses.fields(StepProblem):
        if not f.init:
            continue
        a, b = getattr(problem, f.name), getattr(ref, f.name)
        if isinstance(a, np.ndarray):
            assert a.dtype == b.dtype and a.shape == b.shape and np.array_equal(a, b), f.name
            assert a.flags.c_contiguous, f.name
        else:
            assert a == b, f.name


