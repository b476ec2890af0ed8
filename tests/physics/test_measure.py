"""The internal (squeeze) part of two hands' wrenches (no simulator needed)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dualarm_qp.physics.measure import internal_force, space_of
from dualarm_qp.task.loads import ObjectLoad, rigid_grasp, sliding_grasp, split_load

P_L, P_F = np.array([0.0, 0.0, 0.5]), np.array([0.4, 0.0, 0.5])
RIGID = space_of(np.zeros((6, 0)))
SLIDE = space_of(sliding_grasp(P_F, [1.0, 0.0, 0.0]).free)


def test_a_pure_squeeze_is_all_internal():
    w_l = np.r_[10.0, 0, 0, 0, 0, 0]   # the leader pushes towards the follower
    w_f = np.r_[-10.0, 0, 0, 0, 0, 0]  # and the follower back: no resultant
    size, pair = internal_force((P_L, P_F), (RIGID, RIGID), (w_l, w_f))
    assert size == pytest.approx(10.0, rel=1e-12)
    np.testing.assert_allclose(pair, np.array([w_l, w_f]), atol=1e-12)


@settings(max_examples=30, deadline=None)
@given(st.floats(0.5, 20.0), st.floats(-0.3, 0.3), st.floats(0.0, 0.4))
def test_the_split_of_the_load_has_no_internal_part(mass, cx, cz):
    """The minimum-norm split of a weight is what the hands do without squeezing."""
    load = ObjectLoad(mass, np.array([cx, 0.0, cz]), np.array([0.0, 0.0, -9.81]))
    hands = [rigid_grasp(P_L), sliding_grasp(P_F, [1.0, 0.0, 0.0])]
    split = split_load(hands, load, np.eye(4))
    size, _ = internal_force((P_L, P_F), (RIGID, SLIDE), tuple(split.wrenches))
    assert size < 1e-9 * load.weight


def test_a_squeeze_added_to_the_split_is_found_whole():
    load = ObjectLoad(3.0, np.array([0.2, 0.0, 0.0]), np.array([0.0, 0.0, -9.81]))
    hands = [rigid_grasp(P_L), sliding_grasp(P_F, [1.0, 0.0, 0.0])]
    w = split_load(hands, load, np.eye(4)).wrenches.copy()
    # A vertical squeeze pair (the sliding grasp takes no force along x): +f at the
    # leader, -f at the follower, with the couple the leader's hand must add.
    f = np.array([0.0, 0.0, 7.0])
    w[0, :3] += f
    w[1, :3] -= f
    w[0, 3:] += np.cross(P_F - P_L, -f) * -1.0
    size, _ = internal_force((P_L, P_F), (RIGID, SLIDE), (w[0], w[1]))
    assert size == pytest.approx(7.0, rel=1e-9)
