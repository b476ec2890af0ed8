"""The velocity damper's settings: their checks, the dt rule and the allowed rate."""

from __future__ import annotations

import pytest

from dualarm_qp.collision import CLEARANCE_ALLOWANCE, CollisionSettings
from dualarm_qp.errors import InvalidInputError


@pytest.mark.parametrize(("kw", "match"), [
    ({"safety_distance": -0.01}, "safety_distance"),
    ({"influence_distance": 0.02, "safety_distance": 0.02}, "influence_distance"),
    ({"approach_speed_max": 0.0}, "approach_speed_max"),
    ({"grasp_clearance": float("nan")}, "grasp_clearance"),
])
def test_bad_settings_are_refused(kw, match):
    with pytest.raises(InvalidInputError, match=match):
        CollisionSettings(**kw)


def test_one_step_may_not_cross_the_band():
    s = CollisionSettings(influence_distance=0.1, safety_distance=0.02,
                          approach_speed_max=0.2)
    s.check_dt(0.39)  # xi dt = 0.078 < d_i - d_s = 0.08: allowed
    with pytest.raises(InvalidInputError, match="approach_speed_max"):
        s.check_dt(0.41)


def test_the_allowed_rate_falls_linearly_to_zero_at_the_safety_distance():
    s = CollisionSettings(influence_distance=0.1, safety_distance=0.02,
                          approach_speed_max=0.2)
    assert s.allowed_rate(0.1) == pytest.approx(-0.2)
    assert s.allowed_rate(0.06) == pytest.approx(-0.1)
    assert s.allowed_rate(0.02) == 0.0
    assert s.allowed_rate(0.0) > 0.0  # below d_s the pair must separate
    assert s.summary()["allowance_m"] == CLEARANCE_ALLOWANCE
