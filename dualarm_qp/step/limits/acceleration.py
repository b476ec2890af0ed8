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

import numpy as np
from numpy.typing import NDArray

from ..context import StepContext
from ..parts import Constraint
from .registry import LimitSetup, register_limit

FloatArray = NDArray[np.float64]


def braking_bound(D: FloatArray, delta: FloatArray, dt: float) -> FloatArray:
    """Largest rate from which a stop within the distance ``D`` is possible.

    Parameters
    ----------
    D : ndarray
        Distance to the end of the range [rad or m], ``>= 0`` (``inf``: no end).
    delta : ndarray
        Largest change of rate per sample, ``a dt`` [rad/s or m/s] (``inf``: none).
    dt : float
        Sampling interval [s].

    Returns
    -------
    ndarray
        ``V(D)`` [rad/s or m/s]; ``inf`` where ``D`` or ``delta`` is infinite.
    """
    D = np.asarray(D, dtype=np.float64)
    delta = np.asarray(delta, dtype=np.float64)
    finite = np.isfinite(D) & np.isfinite(delta)
    Dd = np.where(finite, np.maximum(D, 0.0), 0.0)
    dd = np.where(finite, delta, 1.0)
    n = np.floor(0.5 * (-1.0 + np.sqrt(1.0 + 8.0 * Dd / (dd * dt))))
    V = (Dd / dt + dd * n * (n + 1.0) / 2.0) / (n + 1.0)
    return np.where(finite, V, np.inf)


class AccelerationLimit:
    """``|x - x_applied| <= a dt``, intersected with the braking bound of each range end.

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
        self.a_max = a_max
        self.delta = a_max * dt

    def constraint(self, ctx: StepContext) -> Constraint:
        """Return the box around the last applied command, cut by the braking bounds."""
        delta, dt = self.delta, ctx.dt
        x0 = ctx.x_applied
        with np.errstate(invalid="ignore"):
            lower = x0 - delta
            upper = x0 + delta
        # Distances to each end of the range, from the rate ranges of Eqs. 30-36.
        d_up = ctx.rate_hi * dt
        d_lo = -ctx.rate_lo * dt
        v_up = np.where(d_up >= 0.0, braking_bound(d_up, delta, dt), np.inf)
        v_lo = np.where(d_lo >= 0.0, braking_bound(d_lo, delta, dt), np.inf)
        return Constraint(lower=np.maximum(lower, -v_lo), upper=np.minimum(upper, v_up))


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
