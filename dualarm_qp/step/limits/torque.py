"""Quasi-static joint torque limits: the torques of the next sample, linearised, in a box.

Each arm's joints hold the arm and its hand's share of the load (:mod:`dualarm_qp.task.torques`):
``tau(y)``, ``y`` the positions the decision variables are rates of (both arms' joints,
the grasp coordinates). Over one sample ``y`` moves by ``dt x``, so to first order

    -tau_max <= tau(y) + dt D x <= tau_max,     D = d tau / d y,

two rows per joint with a finite ``tau_max``:
``dt D x <= tau_max - tau`` and ``-dt D x <= tau_max + tau``. ``D`` includes the load
split's change as the leader's joints turn the object and as a grasp slides (the wrench a
hand carries depends on where the grasps are), so a sliding grasp can relieve a joint.
The rows hold the next sample's torques to first order; the second-order rest is what
the realised check allows (:mod:`dualarm_qp.control.torques`).

A joint already beyond its limit (a start beyond it is refused before the run) gets a row
that asks its torque back within the limit in one sample.

With ``torque_approach`` ``T`` [s] a joint inside its limit closes at most ``dt / T`` of
its margin per sample (``dt D x <= (dt / T) (tau_max - tau)``, the same for the lower
limit), as the velocity damper of a collision pair: the torque approaches its limit
exponentially (within 0.1% after ``7 T``), and what relieves it (a sliding grasp) starts
before the limit is reached and takes over smoothly. Without it, the row lets the
torque run into its limit at full rate and stops it there within one sample: the motion
that relieves the joint then starts at once, an acceleration that a quasi-static plan
does not see (the follower's shoulder of ``configs/ur5_pair_heavy_bar.yaml`` decelerated
at 9.5 rad/s^2, 1.36 times its limit in MuJoCo's closed loop).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..._compiled import kernel
from ...errors import ShapeError
from ...task.torques import LoadTorques, torque_limits_of
from ..context import StepContext
from ..layout import Layout
from .registry import LimitSetup, register_limit

FloatArray = NDArray[np.float64]

#: Row names of this limit: ``"torque <joint> max"`` / ``"torque <joint> min"``.
ROW_PREFIX = "torque "


class TorqueLimit(kernel.Limit):
    """``|tau + dt D x| <= tau_max`` for every joint with a finite limit.

    A part written in Python (a subclass of the kernel's limit: the step's loop asks its
    :meth:`constraint` in turn).

    Parameters
    ----------
    torques : LoadTorques
        Both arms' statics (their inertias, the load).
    tau_max : ndarray, shape (n_l + n_f,)
        Torque limit of every joint, the leader's first [N m] (``inf``: none).
    layout : Layout
        The slices of the decision vector.
    approach : float, optional
        ``torque_approach`` [s] (module docstring; None: the whole margin in one sample).
    """

    name = "torque"
    gives_rows = True

    def __init__(self, torques: LoadTorques, tau_max: FloatArray, layout: Layout,
                 approach: float | None = None) -> None:
        super().__init__()
        self.approach = approach
        self.torques = torques
        self.tau_max = np.asarray(tau_max, dtype=np.float64)
        if self.tau_max.shape != (layout.n_l + layout.n_f,):
            raise ShapeError("tau_max", (layout.n_l + layout.n_f,), self.tau_max.shape)
        self.layout = layout
        self._rows = np.flatnonzero(np.isfinite(self.tau_max))
        # Every joint limited (the common case): the rows are the arrays themselves.
        self._every = self._rows.size == self.tau_max.size
        names = layout.names
        joints = [names[j] for j in self._rows.tolist()]
        self.row_names = (tuple(f"{ROW_PREFIX}{j} max" for j in joints)
                          + tuple(f"{ROW_PREFIX}{j} min" for j in joints))

    def __reduce__(self) -> tuple[Any, ...]:
        return (TorqueLimit, (self.torques, self.tau_max, self.layout, self.approach))

    def constraint(self, ctx: StepContext) -> Any:
        """Return the two rows of every limited joint at this state (``kernel.Constraint``)."""
        rows = self._rows
        if rows.size == 0:
            return kernel.Constraint()
        s = ctx.state
        st = self.torques.linearised(s.q_l, s.q_f, s.sigma, s.sigma_leader)
        if self._every:
            D, tau, lim = ctx.dt * st.D, st.tau, self.tau_max
        else:
            D = ctx.dt * st.D[rows]
            tau, lim = st.tau[rows], self.tau_max[rows]
        h = np.concatenate((lim - tau, lim + tau))
        if self.approach is not None:  # close a share of the margin (a joint inside it)
            share = min(1.0, ctx.dt / self.approach)
            h = np.where(h > 0.0, share * h, h)
        return kernel.Constraint(G=np.concatenate((D, -D)), h=h, row_names=list(self.row_names))


def _torque(setup: LimitSetup) -> TorqueLimit | None:
    opts = setup.options
    if not opts.torque_limits:
        return None
    task, lay = setup.task, setup.layout
    tau_max = np.full(lay.n_l + lay.n_f, np.inf)
    if setup.leader_bounds:
        tau_max[lay.leader] = torque_limits_of(task.leader, opts.leader_tau_max, "leader")
    tau_max[lay.follower] = torque_limits_of(task.follower, opts.follower_tau_max, "follower")
    return TorqueLimit(LoadTorques(task), tau_max, lay, opts.torque_approach)


register_limit("torque", _torque)

__all__ = ["ROW_PREFIX", "TorqueLimit"]
