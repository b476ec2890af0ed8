"""What a plant measured at the hands, sample by sample, and its columns in the trace.

A plant that measures the hands' wrenches (a cell's force/torque sensors, or the MuJoCo
plant's, :mod:`dualarm_qp.physics.sensors`) hands the controller, with each state, a
:class:`HandReading`: the wrench each hand applies to the object, the internal
(squeeze) part of the pair, the follower's share of the load and the object's pose.
:func:`record_readings` writes them into the trace, one per sample, aligned with the
states the controller was handed (with a measurement delay, both are as old).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .trace import Trace

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class HandReading:
    """The hands' wrenches at one sample, as measured.

    Attributes
    ----------
    leader, follower : ndarray, shape (6,)
        ``[f; m]`` each hand applies to the object [N, N m]: world frame, the moment
        about the hand's grasp point (the convention of :mod:`dualarm_qp.task.loads`).
    internal : float
        Size of the internal (squeeze) force [N]
        (:func:`~dualarm_qp.physics.measure.internal_force`).
    internal_follower : ndarray, shape (6,)
        The follower's internal wrench [N, N m] (the leader's balances it).
    share : float
        The follower's share of what the hands carry along the push direction (up,
        against gravity; a support's normal in Case 2): ``f_f . u / (f_l + f_f) . u``
        (NaN when the hands carry nothing along it).
    object_pose : ndarray, shape (7,)
        The object frame's position [m] and orientation (quaternion ``w, x, y, z``),
        world.
    torque_ratio : float
        The largest share of a joint's torque limit the arms' joints reached over the
        sample (the plant's own torques; NaN: no limits, or a plant that does not
        measure them).
    """

    leader: FloatArray
    follower: FloatArray
    internal: float
    internal_follower: FloatArray
    share: float
    object_pose: FloatArray
    torque_ratio: float = float("nan")


def load_share(leader: FloatArray, follower: FloatArray, up: FloatArray) -> float:
    """Return the follower's share of the force both hands apply along ``up`` (unit)."""
    f_l, f_f = float(leader[:3] @ up), float(follower[:3] @ up)
    total = f_l + f_f
    return f_f / total if abs(total) > 1e-9 else float("nan")


def record_readings(trace: Trace, plant: Any) -> None:
    """Write the plant's readings (``plant.readings``, if it has them) into ``trace``.

    Reading ``k`` belongs to sample ``k`` (the state the controller was handed); samples
    without one keep NaN.
    """
    readings: Sequence[HandReading] | None = getattr(plant, "readings", None)
    if not readings:
        return
    for k, r in enumerate(readings[:len(trace)]):
        trace.wrench_leader[k] = r.leader
        trace.wrench_follower[k] = r.follower
        trace.internal_force[k] = r.internal
        trace.internal_follower[k] = r.internal_follower
        trace.load_share[k] = r.share
        trace.object_pose[k] = r.object_pose
        trace.torque_ratio_measured[k] = r.torque_ratio


__all__ = ["HandReading", "load_share", "record_readings"]
