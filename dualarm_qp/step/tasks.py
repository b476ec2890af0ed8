"""The step's two equality tasks: the object follows ``D(t)``; the grasp stays closed.

Both read the carried-object model's Jacobians from the step's context
(:class:`~dualarm_qp.step.context.StepContext`), in world coordinates ``[v; w]``, and
are one block of twelve rows, assembled by the compiled kernel in one call:

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

from .._compiled import kernel
from ..errors import NonFiniteError
from .context import StepContext
from .parts import Equality

_AXES = ("vx", "vy", "vz", "wx", "wy", "wz")


class CarryTasks:
    """The object follows ``D(t)`` (rows 1-6); the follower's grasp stays closed (7-12).

    Parameters
    ----------
    leader_gain : float
        Feedback gain ``K_l`` [1/s] on the object's pose error to ``D(t)``.
    correction_gain : float
        Feedback gain ``K`` [1/s] on the closure error; 0 disables it.
    exact_orientation : bool
        Keep the curvature term of the follower's grasp frame (False: the paper's frozen
        orientation, Sec. 3.3).

    Attributes
    ----------
    leader_gain, correction_gain : float
        The gains (the controller may change ``leader_gain`` between steps).
    """

    name = "object path and grasp closure"
    row_names = (*(f"object {a}" for a in _AXES), *(f"closure {a}" for a in _AXES))

    def __init__(self, leader_gain: float, correction_gain: float, *,
                 exact_orientation: bool = False) -> None:
        self.leader_gain = float(leader_gain)
        self.correction_gain = float(correction_gain)
        self.exact_orientation = bool(exact_orientation)

    def equality(self, ctx: StepContext) -> Equality:
        """Rows 1-6 ``J_o [ql_dot; m_l] = scale_max V_o(t) + K_l e_l``, then the closure's.

        Rows 7-12: ``J_f qf_dot - J_t [ql_dot; m; m_l] = K e_c``.

        Raises
        ------
        NonFiniteError
            The rows would hold NaN or infinity.
        """
        carry, lay = ctx.carry, ctx.layout
        A = np.empty((12, lay.n))
        b = np.empty(12)
        twist = ctx.task.trajectory.twist(ctx.state.t)
        if not kernel.carry_equality(
                lay.n_l, carry.J_object, carry.J_target, ctx.J_f, twist, ctx.leader_error,
                ctx.closure_error, ctx.scale_max, self.leader_gain, self.correction_gain,
                self.exact_orientation, A, b):
            raise NonFiniteError("the step's equality (D(t), its twist or the arms' poses)")
        return Equality(A, b, self.row_names)


__all__ = ["CarryTasks"]
