"""An integer beyond the largest float is bad input with the library's error.

Python's ``float()`` and numpy's conversions raise a bare ``OverflowError`` for an int
of more than about 309 digits; every public entry point that converts numbers turns it
into a :class:`~dualarm_qp.errors.DualArmError` (a non-finite number, or not numbers).
"""

from __future__ import annotations

import numpy as np
import pytest

from dualarm_qp.errors import DualArmError, NonFiniteError
from dualarm_qp.geometry.shapes import sphere
from dualarm_qp.kinematics import puma560
from dualarm_qp.step.bounds import grasp_rates
from dualarm_qp.step.state import DualArmState
from dualarm_qp.task import LinearTrajectory, PlaneBar, WaypointTrajectory
from dualarm_qp.task.loads import ObjectLoad

HUGE = 10**400


def _beam_controller():
    from pathlib import Path

    from dualarm_qp.experiments import build_experiment, load_config

    path = Path(__file__).resolve().parents[1] / "configs" / "puma_beam_limits.yaml"
    exp = build_experiment(load_config(path), str(path))
    return exp, exp.controller()


@pytest.mark.parametrize("make", [
    lambda: LinearTrajectory([HUGE, 0.0, 0.0], [0.0, 0.0, 0.0], tf=1.0),
    lambda: LinearTrajectory([0.0, 0.0, 0.0], [0.0, 0.0, 0.0], tf=HUGE),
    lambda: WaypointTrajectory([0.0, 1.0], [np.eye(4), np.eye(4)]).pose(HUGE),
    lambda: WaypointTrajectory([0.0, 1.0], [np.eye(4).tolist(),
                                            [[1, 0, 0, HUGE], [0, 1, 0, 0], [0, 0, 1, 0],
                                             [0, 0, 0, 1]]]),
    lambda: puma560(qd_max=[HUGE] * 6),
    lambda: puma560().fk([HUGE, 0, 0, 0, 0, 0]),
    lambda: PlaneBar(r_min=[HUGE, 0.0, 0.0]),
    lambda: sphere(HUGE),
    lambda: grasp_rates(PlaneBar(), 0.1, HUGE),
    lambda: ObjectLoad(HUGE, np.zeros(3), np.array([0.0, 0.0, -9.81])),
], ids=["linear p0", "linear tf", "waypoint t", "waypoint pose", "arm limits", "arm joints",
        "surface box", "sphere radius", "grasp rate dt", "load mass"])
def test_a_huge_integer_is_a_clear_error(make) -> None:
    with pytest.raises(DualArmError):
        make()


def test_a_controller_refuses_a_huge_time() -> None:
    exp, ctrl = _beam_controller()
    s = exp.initial
    with pytest.raises(NonFiniteError):
        ctrl.step(DualArmState(HUGE, s.q_l, s.q_f, s.sigma))
