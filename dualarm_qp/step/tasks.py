"""The step's two equality tasks: the object follows ``D(t)``; the grasp stays closed.

Both read the carried-object model's Jacobians from the step's context
(:class:`~dualarm_qp.step.context.StepContext`), in world coordinates ``[v; w]``:

    J_o [ql_dot; m_l] = s V_o(t) + K_l e_l                       (Eq. 14 differentiated)
    J_f qf_dot - J_t [ql_dot; m; m_l] = K e_c                    (Eqs. 25-27)

``J_o`` is the Jacobian of the object frame (the leader's task, with the path twist
``V_o`` and the feedback of its pose error ``e_l``); ``J_t`` is the Jacobian of the
follower's target frame ``T_l H1 H2(sigma)`` and ``J_f`` the follower's tool Jacobian;
``e_c`` is the grasp closure error. With a rigid leader grasp and a six-joint leader
the first block fixes ``ql_dot`` and the second is the paper's 6x7 follower problem
``[J_f, -R_o s*] [qf_dot; m] = J_l' ql_dot + K e`` (Eqs. 25-27). The paper freezes the
orientation of the follower's grasp (kappa = 0 in Eq. 26) and re-resolves it after the
step (Sec. 3.3); ``exact_orientation=True`` keeps its curvature term instead.
"""

from __future__ import annotations

import numpy as np

from .context import StepContext
from .parts import Equality

_AXES = ("vx", "vy", "vz", "wx", "wy", "wz")


class ObjectPathTask:
    """The object frame follows the desired path ``D(t)`` (the leader's task).

    Parameters
    ----------
    gain : float
        Feedback gain ``K_l`` [1/s] on the object's pose error to ``D(t)``.
    """

    name = "object path"
    row_names = tuple(f"object {a}" for a in _AXES)

    def __init__(self, gain: float) -> None:
        self.gain = float(gain)

    def equality(self, ctx: StepContext) -> Equality:
        """``J_o [ql_dot; m_l] = scale_max V_o(t) + K_l e_l`` (six rows)."""
        lay = ctx.layout
        J = ctx.carry.J_object  # columns: leader joints, then the grasps
        A = np.zeros((6, lay.n))
        A[:, lay.leader] = J[:, :lay.n_l]
        A[:, lay.grasps] = J[:, lay.n_l:]
        b = ctx.scale_max * ctx.task.trajectory.twist(ctx.state.t) + self.gain * ctx.leader_error
        return Equality(A, b, self.row_names)


class GraspClosureTask:
    """The follower's tool moves with its target on the object (Eqs. 25-27).

    Parameters
    ----------
    gain : float
        Feedback gain ``K`` [1/s] on the closure error; 0 disables it.
    exact_orientation : bool
        Keep the curvature term of the follower's grasp frame (False: the paper's frozen
        orientation, Sec. 3.3).
    """

    name = "grasp closure"
    row_names = tuple(f"closure {a}" for a in _AXES)

    def __init__(self, gain: float, *, exact_orientation: bool = False) -> None:
        self.gain = float(gain)
        self.exact_orientation = bool(exact_orientation)

    def equality(self, ctx: StepContext) -> Equality:
        """``J_f qf_dot - J_t [ql_dot; m; m_l] = K e_c`` (six rows)."""
        lay = ctx.layout
        J = ctx.carry.J_target
        A = np.zeros((6, lay.n))
        A[:, lay.leader] = -J[:, :lay.n_l]
        A[:, lay.follower] = ctx.J_f
        A[:, lay.grasps] = -J[:, lay.n_l:]
        if not self.exact_orientation:
            A[3:, lay.grasp_follower] = 0.0  # the paper's frozen grasp orientation
        return Equality(A, self.gain * ctx.closure_error, self.row_names)


__all__ = ["GraspClosureTask", "ObjectPathTask"]
