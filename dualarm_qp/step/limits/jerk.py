"""Jerk limits: every rate within ``j dt^2`` of the last two commands' extrapolation.

A variable with jerk limit ``j`` may change its acceleration by at most ``j dt`` per
sample. With ``x_a`` the last command applied and ``x_p`` the one before it (both zero
when the run starts at rest), the accelerations are ``(x - x_a) / dt`` and ``(x_a - x_p)
/ dt``, so

    |x - (2 x_a - x_p)| <= j dt^2.

This is what a Franka's reflex checks, and what the realised check measures from the
third differences of ``trajectory.csv`` (:mod:`dualarm_qp.control.realised`).

**Reaching a speed limit.** A rate that accelerates towards its speed limit must start
to ease its acceleration off before it gets there: the box also bounds each rate by the
largest ``x`` from which the increments ``d - j dt^2, d - 2 j dt^2, ...`` (``d = x -
x_a``) bring the acceleration to zero without passing ``v_max`` (:func:`speed_bound`),
and likewise towards ``-v_max``. From a rate within it, the next step can always stay
within it.

The jerk box never makes the step infeasible on its own: where it does not meet what the
speed limit, the acceleration limit and the acceleration limit's braking bound near a
range end allow (:mod:`.acceleration`), it gives way for that variable (the speed, the
acceleration and the range come first), and that sample's realised jerk shows it. Near
a range end the braking bound, which assumes the full deceleration at once, is the one
that can ask for that.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..._compiled import kernel
from ..context import StepContext
from .acceleration import braking_bound
from .registry import LimitSetup, register_limit

FloatArray = NDArray[np.float64]


def speed_bound(x_a: FloatArray, v_max: FloatArray, J: FloatArray, A: FloatArray
                ) -> FloatArray:
    """Return the largest rate from which the acceleration can be eased to 0 below ``v_max``.

    With the increment ``d = x - x_a`` eased off by ``J = j dt^2`` per sample, the rate
    reaches ``x + (d - J) + (d - 2 J) + ...`` (the positive terms); for ``m`` samples of
    easing (``(m - 1) J < d <= m J``) that is ``x_a + m d - J m (m - 1) / 2``. The bound
    is the ``x`` where it equals ``v_max``, looked for over ``m = 1 .. ceil(A / J)``
    (``A = a dt``, the largest increment).

    Parameters
    ----------
    x_a : ndarray
        The last command applied [per s].
    v_max, J, A : ndarray
        Speed limit [per s], jerk and acceleration limits as rate changes per sample
        [per s] (``inf``: none).

    Returns
    -------
    ndarray
        The bound [per s] (``inf`` where a limit is infinite).
    """
    out = np.full(np.shape(x_a), np.inf)
    ok = np.isfinite(v_max) & np.isfinite(J)
    if not ok.any():
        return out
    xa, v, j = x_a[ok], v_max[ok], J[ok]
    a = np.where(np.isfinite(A[ok]), A[ok], np.inf)
    m_max = int(min(np.max(np.ceil(np.where(np.isfinite(a), a / j, 1.0))), 10_000))
    best = xa + (v - xa)  # m = 1 (d <= J): x <= v
    for m in range(2, m_max + 1):
        d = (v - xa + j * m * (m - 1) / 2.0) / m
        valid = (d > (m - 1) * j) & (d <= m * j)
        best = np.where(valid, xa + d, best)
    first = v - xa <= j  # the crossing lies in the first segment (m = 1)
    out[ok] = np.where(first, v, best)
    return out


class JerkLimit(kernel.Limit):
    """``|x - (2 x_a - x_p)| <= j dt^2`` where it meets the speed and acceleration boxes.

    A part written in Python (a subclass of the kernel's limit).

    Parameters
    ----------
    j_max : ndarray, shape (n,)
        Jerk limit of every variable [rad/s^3, m/s^3] (``inf``: none).
    a_max : ndarray, shape (n,)
        Acceleration limit of every variable [rad/s^2, m/s^2] (``inf``: none).
    v_max : ndarray, shape (n,)
        Speed limit of every variable [rad/s, m/s] (``inf``: none).
    dt : float
        Sampling interval [s].
    """

    name = "jerk"
    gives_rows = False

    def __init__(self, j_max: FloatArray, a_max: FloatArray, v_max: FloatArray,
                 dt: float) -> None:
        super().__init__()
        self.j_max = np.asarray(j_max, dtype=np.float64)
        self.a_max = np.asarray(a_max, dtype=np.float64)
        self.v_max = np.asarray(v_max, dtype=np.float64)
        self.dt = float(dt)
        self._limited = np.isfinite(self.j_max)

    def __reduce__(self) -> tuple[Any, ...]:
        return (JerkLimit, (self.j_max, self.a_max, self.v_max, self.dt))

    def constraint(self, ctx: StepContext) -> Any:
        """Return the jerk box at this step (``kernel.Constraint``)."""
        dt = self.dt
        x_a = ctx.x_applied
        x_p = x_a if ctx.x_applied_prev is None else ctx.x_applied_prev
        half = np.where(self._limited, self.j_max * dt * dt, np.inf)
        centre = 2.0 * x_a - x_p
        delta = self.a_max * dt
        lo = np.where(self._limited, np.maximum(centre - half,
                                                -speed_bound(-x_a, self.v_max, half, delta)),
                      -np.inf)
        hi = np.where(self._limited, np.minimum(centre + half,
                                                speed_bound(x_a, self.v_max, half, delta)),
                      np.inf)
        # What the speed and acceleration limits allow, with the braking bound of a range
        # end the variable is inside of (rate_lo < 0 < rate_hi inside the range).
        with np.errstate(invalid="ignore"):
            d_lo = np.where(ctx.rate_lo <= 0.0, -ctx.rate_lo * dt, np.inf)
            d_hi = np.where(ctx.rate_hi >= 0.0, ctx.rate_hi * dt, np.inf)
        other_lo = np.maximum(np.maximum(-self.v_max, x_a - delta),
                              -braking_bound(d_lo, delta, dt))
        other_hi = np.minimum(np.minimum(self.v_max, x_a + delta),
                              braking_bound(d_hi, delta, dt))
        # Boxes that touch (a speed limit reached at the most the jerk allows) can be
        # parted by rounding alone: within a few ulps they meet, at the touching point.
        tol = 1e-12 * np.maximum(1.0, np.abs(x_a))
        meets = (lo <= other_hi + tol) & (hi >= other_lo - tol)
        lo, hi = np.minimum(lo, other_hi), np.maximum(hi, other_lo)
        return kernel.Constraint(lower=np.where(meets, lo, -np.inf),
                                 upper=np.where(meets, hi, np.inf))


def _jerk(setup: LimitSetup) -> JerkLimit | None:
    opts = setup.options
    if not opts.jerk_limits:
        return None
    lay, task = setup.layout, setup.task
    j = np.full(lay.n, np.inf)
    a = np.full(lay.n, np.inf)
    v = np.full(lay.n, np.inf)
    j[lay.follower], a[lay.follower] = task.follower.qddd_max, task.follower.qdd_max
    if opts.velocity_limits:
        v[lay.follower] = task.follower.qd_max
        v[lay.grasps] = opts.grasp_speed_max
    if setup.leader_bounds:
        j[lay.leader], a[lay.leader] = task.leader.qddd_max, task.leader.qdd_max
        if opts.velocity_limits:
            v[lay.leader] = task.leader.qd_max
    j[lay.grasps] = opts.grasp_jerk_max
    a[lay.grasps] = opts.grasp_acc_max
    if not opts.acceleration_limits:
        a[:] = np.inf
    return JerkLimit(j, a, v, opts.dt)


register_limit("jerk", _jerk)

__all__ = ["JerkLimit"]
