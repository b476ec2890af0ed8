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

The limit is compiled (``src/kernel/torque_limit.cpp``): it reads the step's context (the
joints, the grasps, the leader's tool and the object's pose, computed once by the step)
and computes ``tau`` and ``D`` as :meth:`~dualarm_qp.task.torques.LoadTorques.linearised`
does, with the kernel's statics and load split. With a Case 2 support the rows are
:meth:`~dualarm_qp.task.torques.LoadTorques.linearised`'s own (:class:`SupportTorqueLimit`,
in Python: a support's push depends on the object's orientation, so the split is
differenced whole).

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
from ...errors import InvalidInputError, ShapeError
from ...task.loads import FALLBACK_LENGTH
from ...task.surfaces import GraspSurface
from ...task.torques import GRASP_STEP, RCOND_MIN, LoadTorques, torque_limits_of
from ..context import StepContext
from ..layout import Layout
from .registry import LimitSetup, register_limit

FloatArray = NDArray[np.float64]

#: Row names of this limit: ``"torque <joint> max"`` / ``"torque <joint> min"``.
ROW_PREFIX = "torque "


def slide_path(surface: GraspSurface) -> Any:
    """Return a surface's sliding path in the kernel's form (``kernel.SlidePath``).

    ``H2(sigma) = P M(rate sigma) C`` (:meth:`~dualarm_qp.task.surfaces.GraspSurface.slide_joint`).
    """
    joint = surface.slide_joint()
    return kernel.SlidePath(joint.kind == "revolute", "xy".index(joint.axis), joint.placement,
                            joint.child, joint.rate)


def _limits(tau_max: FloatArray, layout: Layout) -> tuple[FloatArray, tuple[str, ...]]:
    """Return the limits checked and the row names of the limited joints.

    Raises
    ------
    ShapeError
        Not one limit per joint of both arms.
    InvalidInputError
        A limit that is not > 0.
    """
    tau = np.asarray(tau_max, dtype=np.float64)
    if tau.shape != (layout.n_l + layout.n_f,):
        raise ShapeError("tau_max", (layout.n_l + layout.n_f,), tau.shape)
    if not (tau > 0.0).all():
        raise InvalidInputError("tau_max: every joint's torque limit must be > 0 N m "
                                "(inf: no limit)")
    names = layout.names
    joints = [names[j] for j in np.flatnonzero(np.isfinite(tau)).tolist()]
    return tau, (tuple(f"{ROW_PREFIX}{j} max" for j in joints)
                 + tuple(f"{ROW_PREFIX}{j} min" for j in joints))


class TorqueLimit(kernel.TorqueLimit):
    """``|tau + dt D x| <= tau_max`` for every joint with a finite limit.

    A compiled part (a subclass of the kernel's): ``tau`` and ``D`` from the step's
    context, by the statics of ``torques`` (the arms' inertias and the load; its chains
    are the kernel's) and the load split between its task's grasps. A task whose follower
    supports a load (Case 2) has :class:`SupportTorqueLimit`.

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

    Raises
    ------
    ShapeError
        ``tau_max`` is not one limit per joint of both arms.
    InvalidInputError
        A limit that is not > 0, or a task whose follower supports a load.
    """

    name = "torque"
    gives_rows = True

    def __init__(self, torques: LoadTorques, tau_max: FloatArray, layout: Layout,
                 approach: float | None = None) -> None:
        tau, row_names = _limits(tau_max, layout)
        task, load = torques.task, torques.task.load
        if task.contact is not None and load is not None:
            raise InvalidInputError("a follower that supports the load (Case 2) has the "
                                    "torque rows of SupportTorqueLimit")
        leader, follower = torques.leader, torques.follower
        super().__init__(
            leader.chain, leader.frame, follower.chain, follower.frame, tau, list(row_names),
            None if load is None else load.mass,
            np.zeros(3) if load is None else load.mass_centre,
            leader.gravity if load is None else load.gravity, slide_path(task.surface),
            None if task.leader_surface is None else slide_path(task.leader_surface),
            GRASP_STEP, FALLBACK_LENGTH, RCOND_MIN)
        self.torques = torques
        self.tau_max = tau
        self.layout = layout
        self.row_names = row_names
        if approach is not None:
            self.approach = approach

    def __reduce__(self) -> tuple[Any, ...]:
        return (TorqueLimit, (self.torques, self.tau_max, self.layout,
                              self.approach or None))


class SupportTorqueLimit(kernel.Limit):
    """The torque limit of a follower that supports the load (Case 2), in Python.

    The rows of :class:`TorqueLimit` from :meth:`LoadTorques.linearised`: a support's push
    depends on the object's orientation, so the load split is differenced whole (central
    differences over :data:`~dualarm_qp.task.torques.SPLIT_STEP`). A part written in
    Python (a subclass of the kernel's limit: the step's loop asks its :meth:`constraint`).

    Parameters
    ----------
    torques, tau_max, layout, approach
        As :class:`TorqueLimit`'s.
    """

    name = "torque"
    gives_rows = True

    def __init__(self, torques: LoadTorques, tau_max: FloatArray, layout: Layout,
                 approach: float | None = None) -> None:
        super().__init__()
        self.approach = approach
        self.tau_max, self.row_names = _limits(tau_max, layout)
        self.torques = torques
        self.layout = layout
        self._rows = np.flatnonzero(np.isfinite(self.tau_max))

    def __reduce__(self) -> tuple[Any, ...]:
        return (SupportTorqueLimit, (self.torques, self.tau_max, self.layout, self.approach))

    def constraint(self, ctx: StepContext) -> Any:
        """Return the two rows of every limited joint at this state (``kernel.Constraint``)."""
        rows = self._rows
        if rows.size == 0:
            return kernel.Constraint()
        s = ctx.state
        st = self.torques.linearised(s.q_l, s.q_f, s.sigma, s.sigma_leader)
        D = ctx.dt * st.D[rows]
        tau, lim = st.tau[rows], self.tau_max[rows]
        h = np.concatenate((lim - tau, lim + tau))
        if self.approach is not None:  # close a share of the margin (a joint inside it)
            h = np.where(h > 0.0, min(1.0, ctx.dt / self.approach) * h, h)
        return kernel.Constraint(G=np.concatenate((D, -D)), h=h,
                                 row_names=list(self.row_names))


def _torque(setup: LimitSetup) -> TorqueLimit | SupportTorqueLimit | None:
    opts = setup.options
    if not opts.torque_limits:
        return None
    task, lay = setup.task, setup.layout
    tau_max = np.full(lay.n_l + lay.n_f, np.inf)
    if setup.leader_bounds:
        tau_max[lay.leader] = torque_limits_of(task.leader, opts.leader_tau_max, "leader")
    tau_max[lay.follower] = torque_limits_of(task.follower, opts.follower_tau_max, "follower")
    if task.contact is not None and task.load is not None:
        return SupportTorqueLimit(LoadTorques(task), tau_max, lay, opts.torque_approach)
    return TorqueLimit(LoadTorques(task), tau_max, lay, opts.torque_approach)


register_limit("torque", _torque)

__all__ = ["ROW_PREFIX", "SupportTorqueLimit", "TorqueLimit", "slide_path"]
