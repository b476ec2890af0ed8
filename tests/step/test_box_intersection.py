"""The step's box: the compiled intersection of the limits' boxes against a reference.

The builder hands every limit's lower and upper bounds to ``kernel.intersect_boxes``:
the largest lower and smallest upper bound win, a tie keeps the earlier limit, a box
empty by rounding only is pinned at its lower end and a NaN names its limit. The
reference below is the per-limit loop the builder ran before, written out in numpy.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from test_step_builder import make_task, options

from dualarm_qp._compiled import kernel
from dualarm_qp.errors import InvalidInputError, NonFiniteError, ShapeError
from dualarm_qp.step.build import StepBuilder
from dualarm_qp.step.parts import Constraint
from dualarm_qp.step.stacking import PIN_RTOL, pin_rounding
from dualarm_qp.step.state import DualArmState
from dualarm_qp.task.surfaces import PlaneBar

seeds = st.integers(min_value=0, max_value=2**32 - 1)


def reference(lowers, lower_ids, uppers, upper_ids, n):
    """The builder's former loop: one ``np.where`` per limit, then the pin."""
    lower, upper = np.full(n, -np.inf), np.full(n, np.inf)
    lo_by, up_by = np.full(n, -1), np.full(n, -1)
    for row, k in zip(lowers, lower_ids, strict=True):
        tighter = row > lower
        lo_by[tighter] = k
        lower = np.where(tighter, row, lower)
    for row, k in zip(uppers, upper_ids, strict=True):
        tighter = row < upper
        up_by[tighter] = k
        upper = np.where(tighter, row, upper)
    rounding = (upper < lower) & (lower - upper <= PIN_RTOL * np.maximum(1.0, np.abs(lower)))
    return lower, np.where(rounding, lower, upper), lo_by, up_by


def random_bounds(rng, k, n, sign):
    """``k`` limits' bounds on ``n`` variables: ties, infinities and rounding gaps."""
    values = rng.choice([-2.0, -1.0, 0.0, 0.5, 1.0, 2.0], size=(k, n))  # many ties
    values += rng.normal(0, 1e-10, size=(k, n)) * (rng.random((k, n)) < 0.3)
    values[rng.random((k, n)) < 0.2] = sign * np.inf
    return values


@settings(max_examples=200, deadline=None)
@given(seeds)
def test_the_intersection_equals_the_per_limit_loop(seed):
    rng = np.random.default_rng(seed)
    n, k_lo, k_up = int(rng.integers(1, 16)), int(rng.integers(0, 6)), int(rng.integers(0, 6))
    lowers = random_bounds(rng, k_lo, n, -1.0)
    uppers = random_bounds(rng, k_up, n, 1.0)
    lower_ids = sorted(rng.choice(8, size=k_lo, replace=False).tolist())
    upper_ids = sorted(rng.choice(8, size=k_up, replace=False).tolist())
    got = kernel.intersect_boxes(lowers, lower_ids, uppers, upper_ids, n, PIN_RTOL)
    want = reference(lowers, lower_ids, uppers, upper_ids, n)
    for g, w in zip((got.lower, got.upper, got.lower_by, got.upper_by), want, strict=True):
        np.testing.assert_array_equal(g, w)
    assert got.nan_limit == -1


def test_a_box_empty_by_rounding_is_pinned_and_one_empty_by_more_is_kept():
    lower = np.array([1.0, 1.0, -3e6])
    upper = np.array([1.0 - 1e-12, 1.0 - 1e-6, -3e6 - 1e-4])  # 1e-12: rounding; 1e-6: not
    pinned = pin_rounding(lower, upper)
    assert pinned[0] == 1.0 and pinned[1] == upper[1]
    assert pinned[2] == lower[2]  # relative to |lower|: 1e-4 of 3e6 is rounding


def test_the_first_limit_with_a_nan_bound_is_named():
    nan_row = np.array([0.0, np.nan])
    fine = np.array([0.0, 1.0])
    out = kernel.intersect_boxes(np.array([fine, nan_row]), [0, 3], np.array([nan_row]),
                                 [2], 2, PIN_RTOL)
    assert out.nan_limit == 2


class _Bad:
    """A user's limit whose bounds are broken in a chosen way."""

    gives_rows = False

    def __init__(self, name, lower):
        self.name, self._lower = name, lower

    def constraint(self, ctx):
        return Constraint(lower=self._lower(ctx.layout.n))


@pytest.mark.parametrize(("lower", "error", "words"), [
    (lambda n: np.full(n, np.nan), NonFiniteError, "the bounds of the limit 'broken'"),
    (lambda n: np.zeros(n + 1), ShapeError, "the lower bounds of the limit 'broken'"),
    (lambda n: 0.0, ShapeError, "the lower bounds of the limit 'broken'"),
])
def test_a_users_broken_bounds_are_a_clear_error_naming_the_limit(lower, error, words):
    rng = np.random.default_rng(3)
    task, q_l, q_f, sigma = make_task(rng, PlaneBar())
    builder = StepBuilder(task, options(), limits=(_Bad("broken", lower),))
    with pytest.raises(error, match=words):
        builder.build(DualArmState(0.0, q_l, q_f, sigma))


def test_the_bound_sources_name_the_limit_that_set_each_bound():
    rng = np.random.default_rng(5)
    task, q_l, q_f, sigma = make_task(rng, PlaneBar())

    class Tight:
        name, gives_rows = "tight", False

        def constraint(self, ctx):
            lower = np.full(ctx.layout.n, -np.inf)
            lower[0] = -1e-9  # tighter than any standard limit for the first joint
            return Constraint(lower=lower)

    builder = StepBuilder(task, options(velocity_limits=True), limits=(Tight(),))
    state = DualArmState(0.0, q_l, q_f, sigma)
    for _ in range(2):  # the second build reads the kept pattern
        problem = builder.build(state).problem
        assert problem.lower_by[0] == "tight"
        assert problem.lower_by[1] in ("joint range", "joint speed")
        assert problem.lower[0] == -1e-9


def test_an_infinitely_empty_box_stays_empty():
    lower = np.array([np.inf, 0.0])
    upper = np.array([1.0, -np.inf])
    out = kernel.intersect_boxes(lower[None], [0], upper[None], [1], 2, PIN_RTOL)
    assert out.lower[0] == np.inf and out.upper[0] == 1.0  # not pinned to [inf, inf]
    assert out.upper[1] == -np.inf


def test_pin_rounding_refuses_a_nan_bound():
    with pytest.raises(NonFiniteError):
        pin_rounding(np.zeros(2), np.array([1.0, np.nan]))


def test_a_users_bounds_that_are_not_numbers_are_a_clear_error():
    rng = np.random.default_rng(4)
    task, q_l, q_f, sigma = make_task(rng, PlaneBar())
    builder = StepBuilder(task, options(), limits=(
        _Bad("words", lambda n: np.array(["x"] * n)),))
    with pytest.raises(InvalidInputError, match="the lower bounds of the limit 'words' are not"):
        builder.build(DualArmState(0.0, q_l, q_f, sigma))


@pytest.mark.parametrize("which", ["q_l", "q_f"])
def test_the_builder_checks_the_joints_it_is_given(which):
    rng = np.random.default_rng(6)
    task, q_l, q_f, sigma = make_task(rng, PlaneBar())
    joints = {"q_l": q_l, "q_f": q_f}
    joints[which] = joints[which][:3]
    with pytest.raises(ShapeError, match=which):
        StepBuilder(task, options()).build(DualArmState(0.0, joints["q_l"], joints["q_f"],
                                                        sigma))
    joints[which] = [0.1] * 6  # a list is taken
    StepBuilder(task, options()).build(DualArmState(0.0, joints["q_l"], joints["q_f"], sigma))
