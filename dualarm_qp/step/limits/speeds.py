"""Speed limits: ``|x_i| <= v_max_i`` for the joints and the grasps.

The paper's closing remark intersects the position boxes with the speed limits; the
step does so when ``velocity_limits`` is on: the arms' ``qd_max`` (the leader's only for
a solver that claims hard limits) and ``grasp_speed_max`` for every sliding grasp.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..._compiled import kernel
from .registry import LimitSetup, register_limit

FloatArray = NDArray[np.float64]


class SpeedLimit(kernel.SpeedLimit):
    """The box ``[-v_max, v_max]`` on some variables (a compiled part).

    Parameters
    ----------
    name : str
        ``"joint speed"`` or ``"grasp speed"``.
    v_max : ndarray, shape (n,)
        Speed limit of every variable [rad/s, m/s] (``inf`` for the others).
    """

    gives_rows = False

    def __init__(self, name: str, v_max: FloatArray) -> None:
        super().__init__(v_max)
        self.name = name
        self.v_max = v_max

    def __reduce__(self) -> tuple[Any, ...]:
        return (SpeedLimit, (self.name, self.v_max))


def _joint_speed(setup: LimitSetup) -> SpeedLimit | None:
    if not setup.options.velocity_limits:
        return None
    lay, task = setup.layout, setup.task
    v = np.full(lay.n, np.inf)
    v[lay.follower] = task.follower.qd_max
    if setup.leader_bounds:
        v[lay.leader] = task.leader.qd_max
    return SpeedLimit("joint speed", v)


def _grasp_speed(setup: LimitSetup) -> SpeedLimit | None:
    if not setup.options.velocity_limits:
        return None
    v = np.full(setup.layout.n, np.inf)
    v[setup.layout.grasps] = setup.options.grasp_speed_max
    return SpeedLimit("grasp speed", v)


register_limit("joint speed", _joint_speed)
register_limit("grasp speed", _grasp_speed)

__all__ = ["SpeedLimit"]
