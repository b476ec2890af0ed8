"""The sliding grasp on hardware: estimated from both arms' measured joints.

A sliding palm has no encoder. Each sample, the follower's grasp coordinate is taken
from where the two arms put the hand:

1. the object's pose is the leader's tool pose times the rigid grasp ``H1`` (the leader
   holds the object rigidly: its hand *is* the object's frame);
2. the follower's tool point is written in the object frame;
3. the estimate is the coordinate of the sliding path's point nearest to it
   (:meth:`GraspSurface.sigma_of <dualarm_qp.task.surfaces.GraspSurface.sigma_of>`: the
   projection on a straight grasp line, the nearest point on an arc).

What is left, the distance from the follower's tool to that point and the turn between
the tool frame and the grasp frame there, is the **closure error** of the estimate: the
part of the measured state that no grasp coordinate explains (the servos' lag, a
flexible link, a calibration error of a base). The controller sees it as its closure
error and corrects it through its feedback term, as it does any measured error.

What the estimate assumes: the leader's grasp is rigid and the object is rigid; the arms'
kinematic models and bases are those of the experiment file; the hand stays on the
grasp line (the estimate cannot tell a hand that slid from a hand that left the line:
both show as closure error, which is why it is recorded and judged).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from ..task.scene import DualArmTask

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class GraspEstimate:
    """One sample's grasp estimate.

    Attributes
    ----------
    sigma : float
        The follower's grasp coordinate [m] (not clipped to the grasp range).
    closure_pos : float
        Distance from the follower's tool to the grasp point at ``sigma`` [m].
    closure_rot : float
        Rotation between the follower's tool frame and the grasp frame there [rad].
    """

    sigma: float
    closure_pos: float
    closure_rot: float


def estimate_grasp(task: DualArmTask, q_l: FloatArray, q_f: FloatArray) -> GraspEstimate:
    """Estimate the follower's grasp coordinate from both arms' joints (see the module).

    Parameters
    ----------
    task : DualArmTask
        The task (a rigid leader grasp, a follower that grasps: Case 1).
    q_l, q_f : ndarray
        Measured joints of the leader and the follower [rad].
    """
    T_obj = task.object_pose(np.asarray(q_l, dtype=np.float64))
    T_f = task.follower.fk(np.asarray(q_f, dtype=np.float64))
    p_obj = T_obj[:3, :3].T @ (T_f[:3, 3] - T_obj[:3, 3])
    sigma = float(task.surface.sigma_of(p_obj))
    target = T_obj @ task.surface.pose(sigma)
    pos = float(np.linalg.norm(target[:3, 3] - T_f[:3, 3]))
    rot = float(np.linalg.norm(pin.log3(target[:3, :3] @ T_f[:3, :3].T)))
    return GraspEstimate(sigma, pos, rot)


__all__ = ["GraspEstimate", "estimate_grasp"]
