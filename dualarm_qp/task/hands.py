"""The load each hand of a task carries at a state: the task's grasps in the statics of loads.

:mod:`.loads` holds the statics of the carried object (what a grasp can transmit, the
minimum-norm split of the load); here the task places them: the object by the leader's
kinematics, the grasp points and directions by the surfaces, a support's push by its
support line.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidInputError
from .loads import GraspStatics, LoadSplit, rigid_statics, sliding_statics, split_load, support_push
from .scene import DualArmTask

FloatArray = NDArray[np.float64]


def hand_statics(task: DualArmTask, q_l: Any, sigma: float, sigma_l: float = 0.0
                 ) -> tuple[list[GraspStatics], FloatArray]:
    """Return what each hand can transmit at a state, and the object's pose (world frame).

    The object is placed by the leader, ``T_world_object = leader.fk(q_l) H1(sigma_l)``;
    the grasp points are the leader's tool point and the follower's contact point on
    the object, ``T_world_object H2(sigma)``. A support's push is the support line's
    at this orientation (docs/support.md).

    Returns
    -------
    hands : list of GraspStatics
        The leader's, then the follower's.
    T_world_object : ndarray, shape (4, 4)

    Raises
    ------
    SupportLostError
        A support that would have to pull here.
    """
    T_tool = task.leader.fk(np.asarray(q_l, dtype=float))
    T_obj = T_tool @ task.H1_at(sigma_l)
    R, p = T_obj[:3, :3], T_obj[:3, 3]
    ls = task.leader_surface
    # The points and directions come from the leader's checked kinematics and the
    # surfaces (which check sigma): the grasps are made without a second check.
    leader = (rigid_statics(T_tool[:3, 3]) if ls is None else
              sliding_statics(T_tool[:3, 3], R @ ls.tangent(sigma_l),
                              R @ ls.angular_rate(sigma_l)))
    contact = task.contact
    if contact is not None:
        line = contact.line(R)
        h = contact.force(line, sigma)
        follower = support_push(R @ line.point(sigma) + p, R @ line.normal(sigma), h)
    else:
        s = task.surface
        follower = sliding_statics(R @ s.point(sigma) + p, R @ s.tangent(sigma),
                                   R @ s.angular_rate(sigma))
    return [leader, follower], T_obj


def hand_wrenches(task: DualArmTask, q_l: Any, sigma: float, sigma_l: float = 0.0
                  ) -> LoadSplit:
    """Return the wrench each hand applies to the object at a state (minimum-norm split).

    Raises
    ------
    InvalidInputError
        The task has no load.
    UnbalancedLoadError
        The grasps cannot hold the load here.
    SupportLostError
        A support that would have to pull here.
    """
    if task.load is None:
        raise InvalidInputError("the task has no load (object mass)")
    hands, T_obj = hand_statics(task, q_l, sigma, sigma_l)
    return split_load(hands, task.load, T_obj)


__all__ = ["hand_statics", "hand_wrenches"]
