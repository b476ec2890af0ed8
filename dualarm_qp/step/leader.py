"""The leader's step problem: track ``D(t)`` within the leader's own limits.

The leader holds the object rigidly, so its tool must move with the object's twist
carried to the leader's tool origin, plus a feedback of its pose error:

    J_l ql_dot = s_max V_l(t) + K_l e_l                      (Eq. 14 differentiated)

with ``V_l = [v_o + w_o x (p_l - p_o); w_o]`` from the path's twist ``[v_o; w_o]``,
``e_l`` the pose error of the leader's tool to ``D(t) H1^-1`` [m, rad] and ``K_l`` the
tracking gain [1/s]. ``s_max`` in [0, 1] slows the feed-forward part (the path's end
falls inside this sample). The leader's joint ranges and speed limits give the same
kind of box as the follower's (Eqs. 34-36), so the leader's step is a
:class:`~dualarm_qp.step.StepProblem` with a square ``A = J_l`` (no redundancy for a
six-joint leader): one solution, or, when it leaves the box, the policy's answer (the
largest task scale that fits, a relaxed step, or a stop naming the joint).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..errors import NonFiniteError
from ..se3 import compose_rows, pose_error_rows
from ..task.scene import DualArmTask
from .build import StepOptions, _clip_rates
from .problem import StepProblem

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class LeaderBuild:
    """The leader's step problem and its tracking error.

    Attributes
    ----------
    problem : StepProblem
        ``A = J_l``, ``b = s_max V_l + K_l e_l`` [m/s; rad/s], the leader's rate box.
    error : ndarray, shape (6,)
        Leader tool pose error to its target ``D(t) H1^-1`` [m, rad].
    recovering : ndarray of bool, shape (n_l,)
        Leader joints that start outside their range.
    """

    problem: StepProblem
    error: FloatArray
    recovering: NDArray[np.bool_]


class LeaderStepBuilder:
    """Builds the leader's step problems of one task under fixed options.

    Parameters
    ----------
    task : DualArmTask
        Arms, object and path.
    options : StepOptions
        ``dt`` and whether speed limits apply (``velocity_limits``).
    gain : float
        Tracking feedback gain ``K_l`` [1/s].
    bounds : bool
        Impose the leader's joint ranges and speed limits (hard-limit solvers); False
        leaves the box open (the paper's methods, which ignore limits by design).
    """

    def __init__(self, task: DualArmTask, options: StepOptions, gain: float, *,
                 bounds: bool) -> None:
        leader = task.leader
        n = leader.n
        self.task = task
        self.dt = options.dt
        self.gain = gain
        self.names: tuple[str, ...] = tuple(f"ql{i + 1}" for i in range(n))
        inf = math.inf
        self._q_min = leader.q_min.tolist() if bounds else [-inf] * n
        self._q_max = leader.q_max.tolist() if bounds else [inf] * n
        self._v_max = (leader.qd_max.tolist() if bounds and options.velocity_limits
                       else [inf] * n)
        weights = np.ones(n)
        weights.flags.writeable = False
        self._weights = weights
        self._H1_inv = (None if np.array_equal(task.H1, np.eye(4))
                        else task.H1_inv.tolist())

    def build(self, t: float, q_l: FloatArray, T_l: FloatArray, J_l: FloatArray, *,
              scale_max: float = 1.0) -> LeaderBuild:
        """Build the leader's problem at path time ``t`` [s] and joints ``q_l`` [rad].

        ``(T_l, J_l)`` is ``leader.fk_jacobian(q_l)``; ``scale_max`` in [0, 1] scales the
        path's feed-forward twist (1: full speed).
        """
        traj = self.task.trajectory
        D = traj.pose(t).tolist()
        V = traj.twist(t).tolist()
        target = D if self._H1_inv is None else compose_rows(D, self._H1_inv)
        # Velocity of the leader's tool origin: v_o + w_o x (p_l - p_o).
        r0 = target[0][3] - D[0][3]
        r1 = target[1][3] - D[1][3]
        r2 = target[2][3] - D[2][3]
        w0, w1, w2 = V[3], V[4], V[5]
        V_l = [V[0] + (w1 * r2 - w2 * r1), V[1] + (w2 * r0 - w0 * r2),
               V[2] + (w0 * r1 - w1 * r0), w0, w1, w2]
        err = pose_error_rows(target, T_l.tolist())
        gain = self.gain
        b = [scale_max * v + gain * e for v, e in zip(V_l, err, strict=True)]
        if not math.isfinite(sum(b)):
            raise NonFiniteError("leader twist (D(t) or the leader's pose)")
        dt = self.dt
        q = q_l.tolist()
        lo = [(lo_i - q_i) / dt for lo_i, q_i in zip(self._q_min, q, strict=True)]
        hi = [(hi_i - q_i) / dt for hi_i, q_i in zip(self._q_max, q, strict=True)]
        lower, upper, center, recovering = _clip_rates(lo, hi, self._v_max, 0.0)
        problem = StepProblem.trusted(
            J_l, np.array(b), self._weights, np.array(center), np.array(lower),
            np.array(upper), names=self.names, n_grasp=0,
        )
        return LeaderBuild(problem, np.array(err), np.array(recovering))


__all__ = ["LeaderBuild", "LeaderStepBuilder"]
