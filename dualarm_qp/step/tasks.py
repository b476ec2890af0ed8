"""The step's two equality tasks: the object follows ``D(t)``; the grasp stays closed.

Both read the carried-object model's Jacobians from the step's context
(:class:`~dualarm_qp.step.context.StepContext`), in world coordinates ``[v; w]``; each
is a compiled part (``kernel.ObjectPathTask``, ``kernel.GraspClosureTask``) of six rows:

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

from typing import Any

from .._compiled import kernel

_AXES = ("vx", "vy", "vz", "wx", "wy", "wz")


class ObjectPathTask(kernel.ObjectPathTask):
    """The object follows ``D(t)``: ``J_o [ql_dot; m_l] = scale_max V_o(t) + K_l e_l``.

    Parameters
    ----------
    gain : float
        Feedback gain ``K_l`` [1/s] on the object's pose error to ``D(t)`` (the
        controller may change it between steps: ``task.gain``).
    """

    name = "object path"
    row_names = tuple(f"object {a}" for a in _AXES)

    def __init__(self, gain: float) -> None:
        super().__init__(float(gain))

    def __reduce__(self) -> tuple[Any, ...]:
        return (ObjectPathTask, (self.gain,))


class GraspClosureTask(kernel.GraspClosureTask):
    """The follower's grasp stays closed: ``J_f qf_dot - J_t [ql_dot; m; m_l] = K e_c``.

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
        super().__init__(float(gain), bool(exact_orientation))

    def __reduce__(self) -> tuple[Any, ...]:
        return (_closure, (self.gain, self.exact_orientation))


def _closure(gain: float, exact_orientation: bool) -> GraspClosureTask:
    return GraspClosureTask(gain, exact_orientation=exact_orientation)


#: The standard tasks' row names, in the step's order.
ROW_NAMES = ObjectPathTask.row_names + GraspClosureTask.row_names

__all__ = ["ROW_NAMES", "GraspClosureTask", "ObjectPathTask"]
