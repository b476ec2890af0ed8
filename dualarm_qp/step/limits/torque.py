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
    """

    name = "torque"
    gives_rows = True

    def __init__(self, torques: LoadTorques, tau_max: FloatArray, layout: Layout) -> None:
        super().__init__()
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
        return (TorqueLimit, (self.torques, self.tau_max, self.layout))

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
        return kernel.Constraint(G=np.concatenate((D, -D)),
                                 h=np.concatenate((lim - tau, lim + tau)),
                                 row_names=list(self.row_names))


def _torque(setup: LimitSetup) -> TorqueLimit | None:
    opts = setup.options
    if not opts.torque_limits:
        return None
    task, lay = setup.task, setup.layout
    tau_max = np.full(lay.n_l + lay.n_f, np.inf)
    if setup.leader_bounds:
        tau_max[lay.leader] = torque_limits_of(task.leader, opts.leader_tau_max, "leader")
    tau_max[lay.follower] = torque_limits_of(task.follower, opts.follower_tau_max, "follower")
    return TorqueLimit(LoadTorques(task), tau_max, lay)


register_limit("torque", _torque)

__all__ = ["ROW_PREFIX", "TorqueLimit"]
