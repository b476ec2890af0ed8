"""Both arms' kinematics of one step, in one compiled call.

The step reads, at one state: the carried-object model's poses and Jacobians (the
leader's tool, the object, the follower's target; :class:`~dualarm_qp.task.carry.CarryModel`),
the follower's tool pose and Jacobian, the two pose errors of the step (the object to
``D(t)``, the follower's tool to its target; the convention of
:func:`~dualarm_qp.se3.pose_error`) and both arms' smallest singular values. One call
into the kernel computes all of them (``src/kernel/step_kinematics.cpp``, on Pinocchio's
C++ kinematics and ``log3``) for the builder's context; :func:`both_errors` gives the two
errors alone, from the poses, for the look-ahead's prediction at the next sample.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .._compiled import kernel
from ..kinematics.arm import SerialArm
from ..task.carry import CarryKinematics, CarryModel

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class BothArms:
    """Both arms' kinematics at one state (world frame, SI).

    Attributes
    ----------
    carry : CarryKinematics
        Leader, object and target poses and Jacobians.
    T_f : ndarray, shape (4, 4)
        Follower tool pose [m].
    J_f : ndarray, shape (6, n_f)
        Follower tool Jacobian ``[v; w]``.
    leader_error : ndarray, shape (6,)
        ``[dp; dw]`` from the object frame to ``D(t)`` [m, rad].
    closure_error : ndarray, shape (6,)
        ``[dp; dw]`` from the follower's tool to its target [m, rad].
    sigma_min : tuple of float
        Smallest singular value of the leader's and the follower's tool Jacobian.
    """

    carry: CarryKinematics
    T_f: FloatArray
    J_f: FloatArray
    leader_error: FloatArray
    closure_error: FloatArray
    sigma_min: tuple[float, float]


def both_arms(carry: CarryModel, follower: SerialArm, q_l: FloatArray, q_f: FloatArray,
              sigma_f: float, sigma_l: float, T_D: FloatArray) -> BothArms:
    """Return both arms' kinematics at the state, with the errors to ``T_D`` and the target.

    Parameters
    ----------
    carry : CarryModel
        The leader's carried-object model.
    follower : SerialArm
        The follower arm.
    q_l, q_f : ndarray
        Joints [rad] (finite, of the arms' lengths: checked by the caller).
    sigma_f, sigma_l : float
        Grasp coordinates [m].
    T_D : ndarray, shape (4, 4)
        The object's desired pose ``D(t)``.
    """
    q = carry.configuration(q_l, sigma_f, sigma_l)
    T = np.empty((16, 4))
    J = np.empty((18, q.shape[0]))
    J_f = np.empty((6, follower.n))
    e = np.empty(12)
    sv = np.empty(2)
    kernel.step_kinematics(carry.chain, q, carry.frames, follower.chain, q_f,
                           follower.tool_frame_id, T_D, carry.n_l, T, J, J_f, e, sv)
    return BothArms(carry.kinematics(T[:12], J), T[12:16], J_f, e[:6], e[6:],
                    (float(sv[0]), float(sv[1])))


def both_errors(carry: CarryModel, follower: SerialArm, q_l: FloatArray, q_f: FloatArray,
                sigma_f: float, sigma_l: float, T_D: FloatArray) -> FloatArray:
    """Return :func:`both_arms`' two pose errors alone, from the poses (no Jacobians).

    Returns
    -------
    ndarray, shape (12,)
        ``[dp; dw]`` from the object frame to ``T_D``, then from the follower's tool to
        its target [m, rad].
    """
    e = np.empty(12)
    kernel.step_errors(carry.chain, carry.configuration(q_l, sigma_f, sigma_l), carry.frames,
                       follower.chain, q_f, follower.tool_frame_id, T_D, e)
    return e


__all__ = ["BothArms", "both_arms", "both_errors"]
