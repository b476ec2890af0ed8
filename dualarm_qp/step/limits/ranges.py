"""Range limits: the joints' and the grasps' position ranges as rate boxes (Eqs. 30-36).

Over one sample a variable at position ``q`` with range ``[q_min, q_max]`` may move at
a rate in ``[(q_min - q) / dt, (q_max - q) / dt]`` (Eqs. 34-36 for a joint; Eqs. 30-33
for a grasp, whose range is also cut by the object's box of Eq. 3). The step context
holds these rate ranges (``rate_lo``, ``rate_hi``).

**Recovery.** A variable that starts outside its range cannot get back within one
sample under a speed limit. It may then never move further out: below its range its
lower bound is 0 (it may stay), above it its upper bound is 0; the centring cost
(Eqs. 39-40) pulls it back. With ``recovery_fraction > 0`` it must also move back at
least at that share of its speed limit (a forced return rate can make a step
infeasible).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..._compiled import kernel
from .registry import LimitSetup, register_limit

FloatArray = NDArray[np.float64]


class RangeLimit(kernel.RangeLimit):
    """Rate boxes from the position ranges of some variables, with recovery.

    A compiled part: ``[rate_lo, rate_hi]``, opened towards the range for a variable
    outside it: below the range not further down, back at least at the recovery rate
    (the kernel's ``range_box``, src/kernel/boxes.cpp).

    Parameters
    ----------
    name : str
        ``"joint range"`` or ``"grasp range"``.
    mask : ndarray of bool, shape (n,)
        The variables it bounds.
    speed : ndarray, shape (n,)
        Speed limits [rad/s, m/s] (for the recovery rate; ``inf`` for none).
    recovery_fraction : float
        Share of the speed limit at which a variable outside its range must move back.
    """

    gives_rows = False

    def __init__(self, name: str, mask: NDArray[np.bool_], speed: FloatArray,
                 recovery_fraction: float) -> None:
        rec = (recovery_fraction * np.where(mask, speed, 0.0)
               if recovery_fraction > 0.0 else np.zeros(mask.shape))
        super().__init__(rec, ~mask)
        self.name = name
        self.mask = mask
        self._args = (name, mask, speed, recovery_fraction)

    def __reduce__(self) -> tuple[Any, ...]:
        return (RangeLimit, self._args)


def _speeds(setup: LimitSetup) -> FloatArray:
    """Return the speed limit of every variable [rad/s, m/s] (``inf`` where none is imposed)."""
    lay, task, opts = setup.layout, setup.task, setup.options
    v = np.full(lay.n, np.inf)
    if opts.velocity_limits:
        v[lay.leader] = task.leader.qd_max
        v[lay.follower] = task.follower.qd_max
        v[lay.grasps] = opts.grasp_speed_max
    return v


def _joint_range(setup: LimitSetup) -> RangeLimit:
    lay = setup.layout
    mask = np.zeros(lay.n, dtype=bool)
    mask[lay.follower] = True
    mask[lay.leader] = setup.leader_bounds
    return RangeLimit("joint range", mask, _speeds(setup), setup.options.recovery_fraction)


def _grasp_range(setup: LimitSetup) -> RangeLimit:
    lay = setup.layout
    mask = np.zeros(lay.n, dtype=bool)
    mask[lay.grasps] = True
    return RangeLimit("grasp range", mask, _speeds(setup), setup.options.recovery_fraction)


register_limit("joint range", _joint_range)
register_limit("grasp range", _grasp_range)

__all__ = ["RangeLimit"]
