"""Acceleration limits, with a braking bound that keeps a stop inside the range possible.

Every rate stays within ``a dt`` of the last applied command.

A variable with acceleration limit ``a`` may change its rate by at most ``delta = a dt``
per sample:

    |x - x_applied| <= delta

where ``x_applied`` is the last command applied (not the solver's warm start; zero
when the run starts at rest). Near the end of its range that is not enough: a variable
moving towards the end at speed ``v`` needs several samples to stop. With ``D`` the
distance left to the end of the range, the **exact discrete braking bound**

    V(D) = (D / dt + delta n (n + 1) / 2) / (n + 1),
    n = floor((-1 + sqrt(1 + 8 D / (delta dt))) / 2),

is the largest rate from which the samples at ``V, V - delta, ..., V - n delta`` cover
exactly ``D`` and stop (``n`` is the number of whole braking samples). Bounding the
rate towards each end of the range by ``V`` of the distance to that end keeps the
limits feasible at the next sample: from ``x <= V(D)`` the rate ``x - delta`` is within
``V(D - x dt)``. ``docs/derivation.md`` derives it and compares it with the continuous
rule ``sqrt(2 a D)``. A variable outside its range has no braking bound towards that end
(its range limit already forbids moving further out).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..._compiled import kernel
from .registry import LimitSetup, register_limit

FloatArray = NDArray[np.float64]


def braking_bound(D: FloatArray, delta: FloatArray, dt: float | FloatArray) -> FloatArray:
    """Largest rate from which a stop within the distance ``D`` is possible.

    Computed by the kernel (``src/kernel/standard_parts.cpp``), the one implementation, which
    the step's acceleration box uses too.

    Parameters
    ----------
    D : ndarray
        Distance to the end of the range [rad or m], ``>= 0`` (``inf``: no end).
    delta : ndarray
        Largest change of rate per sample, ``a dt`` [rad/s or m/s] (``inf``: none).
    dt : float or ndarray
        Sampling interval [s].

    Returns
    -------
    ndarray
        ``V(D)`` [rad/s or m/s], of the broadcast shape of the arguments; ``inf``
        where ``D`` or ``delta`` is infinite.
    """
    D_, delta_, dt_ = np.broadcast_arrays(np.asarray(D, dtype=np.float64),
                                          np.asarray(delta, dtype=np.float64),
                                          np.asarray(dt, dtype=np.float64))
    V = kernel.braking_bound(np.ravel(D_), np.ravel(delta_), np.ravel(dt_))
    return V.reshape(D_.shape)


class AccelerationLimit(kernel.AccelerationLimit):
    """``|x - x_applied| <= a dt``, intersected with the braking bound of each range end.

    A compiled part: the box around the last applied command, cut by the braking bounds
    (the distances to each end of the range come from the rate ranges of Eqs. 30-36).

    Parameters
    ----------
    a_max : ndarray, shape (n,)
        Acceleration limit of every variable [rad/s^2, m/s^2] (``inf`` for none).
    dt : float
        Sampling interval [s].
    """

    name = "acceleration"
    gives_rows = False

    def __init__(self, a_max: FloatArray, dt: float) -> None:
        delta = a_max * dt
        super().__init__(delta)
        self.a_max = a_max
        self.delta = delta
        self._dt = dt

    def __reduce__(self) -> tuple[Any, ...]:
        return (AccelerationLimit, (self.a_max, self._dt))


def _acceleration(setup: LimitSetup) -> AccelerationLimit | None:
    opts = setup.options
    if not opts.acceleration_limits:
        return None
    lay, task = setup.layout, setup.task
    a = np.full(lay.n, np.inf)
    a[lay.follower] = task.follower.qdd_max
    if setup.leader_bounds:
        a[lay.leader] = task.leader.qdd_max
    a[lay.grasps] = opts.grasp_acc_max
    return AccelerationLimit(a, opts.dt)


register_limit("acceleration", _acceleration)

__all__ = ["AccelerationLimit", "braking_bound"]
