"""The carried object as part of the leader's kinematic model: grasps are joints.

One Pinocchio model holds the leader arm (its base and tool), the object frame and a
one-dof virtual joint per sliding grasp (:meth:`GraspSurface.slide_joint`: prismatic
along a straight path, revolute about the centre of curvature of an arc):

    leader base -> leader joints -> tool --[leader grasp joint]--> object
                                                      object --[follower grasp joint]--> target

``target`` is the pose the follower's tool must take (Eq. 15). Its frame Jacobian with
respect to ``[q_l, sigma_f, sigma_l]`` is the leader side and the sliding column of
Eqs. 25-27 at once; the object frame's Jacobian is the leader's task (Eq. 14). With a
rigid leader grasp the object frame sits at ``T_l H1``; with a sliding leader grasp at
``T_l G_l(sigma_l)^-1``, where ``G_l(sigma_l) = P M(rate sigma_l) C`` is the leader's
grasp on its own path, so that its inverse is ``C^-1 M(-rate sigma_l) P^-1``.

Every quantity is computed in one call of the compiled kernel per state
(:meth:`CarryModel.update`, on the kernel's copy of the model,
:mod:`~dualarm_qp.kinematics.compiled`) and read from there by the step builder, the
trace and the checks.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from ..errors import InvalidInputError
from ..kinematics.arm import SerialArm
from ..kinematics.compiled import compiled_chain, set_frame_placement, set_joint_placement
from .surfaces import GraspSurface, SlideJoint

FloatArray = NDArray[np.float64]

_JOINTS = {("prismatic", "x"): pin.JointModelPX, ("prismatic", "y"): pin.JointModelPY,
           ("revolute", "x"): pin.JointModelRX, ("revolute", "y"): pin.JointModelRY}


def _se3(T: FloatArray) -> pin.SE3:
    return pin.SE3(np.array(T[:3, :3]), np.array(T[:3, 3]))


@dataclass(frozen=True)
class CarryKinematics:
    """The carried object's kinematics at one state (world frame, SI).

    Attributes
    ----------
    T_tool : ndarray, shape (4, 4)
        Leader tool pose ``T_world_leader`` [m].
    J_tool : ndarray, shape (6, n_l)
        Leader tool Jacobian ``[v; w]`` per joint rate (``LOCAL_WORLD_ALIGNED``).
    T_object : ndarray, shape (4, 4)
        Object pose ``T_world_object`` [m].
    J_object : ndarray, shape (6, n_l + k)
        Object frame Jacobian over ``[q_l, grasp rates]`` [m/s, rad/s per rad/s or m/s].
    T_target : ndarray, shape (4, 4)
        Follower target ``T_world_object H2(sigma_f)`` [m] (Eq. 15).
    J_target : ndarray, shape (6, n_l + k)
        Target frame Jacobian over ``[q_l, sigma_f rate, sigma_l rate]``: its grasp
        columns are per m/s of sliding speed.
    """

    T_tool: FloatArray
    J_tool: FloatArray
    T_object: FloatArray
    J_object: FloatArray
    T_target: FloatArray
    J_target: FloatArray


class CarryModel:
    """Leader arm, object and sliding grasps as one Pinocchio model.

    Parameters
    ----------
    leader : SerialArm
        The leader (its model carries its base and tool).
    surface : GraspSurface
        The follower's sliding path, object coordinates.
    H1 : ndarray, shape (4, 4)
        ``T_leader_object`` for a rigid leader grasp (ignored when ``leader_surface``
        is given).
    leader_surface : GraspSurface, optional
        The leader's sliding path on the object (object coordinates); None: the leader
        grasps rigidly.

    Attributes
    ----------
    n_l : int
        Leader joints.
    n_grasp : int
        Sliding grasps: 1 (follower) or 2 (follower, then leader).
    """

    def __init__(self, leader: SerialArm, surface: GraspSurface, H1: FloatArray,
                 leader_surface: GraspSurface | None = None) -> None:
        model = pin.Model(leader.model)
        tool = model.frames[leader.tool_frame_id]
        parent, at_parent = tool.parentJoint, pin.SE3(tool.placement)
        self.n_l = leader.n
        self._rates: list[float] = []
        if leader_surface is None:
            object_at = at_parent * _se3(H1)
        else:
            joint = leader_surface.slide_joint()
            # G_l^-1 = C^-1 M(-rate sigma_l) P^-1: the joint frame is C^-1 from the tool.
            parent = model.addJoint(parent, _JOINTS[(joint.kind, joint.axis)](),
                                    at_parent * _se3(joint.child).inverse(), "grasp_leader")
            object_at = _se3(joint.placement).inverse()
            self._leader_rate = -joint.rate
        self._object = model.addFrame(pin.Frame("object", parent, 0, object_at,
                                                pin.FrameType.OP_FRAME))
        joint_f: SlideJoint = surface.slide_joint()
        follower_joint = model.addJoint(
            parent, _JOINTS[(joint_f.kind, joint_f.axis)](), object_at * _se3(joint_f.placement),
            "grasp_follower")
        self._target = model.addFrame(pin.Frame("target", follower_joint, 0,
                                                _se3(joint_f.child), pin.FrameType.OP_FRAME))
        self._follower_joint, self._follower_at = follower_joint, object_at
        self._follower_kind = (joint_f.kind, joint_f.axis)
        self._tool = leader.tool_frame_id
        self._follower_rate = joint_f.rate
        self.n_grasp = 1 if leader_surface is None else 2
        # Configuration order is Pinocchio's: [q_l, (grasp_leader), grasp_follower].
        # Decision order is [q_l, sigma_f, (sigma_l)]: columns are permuted below.
        n_l = self.n_l
        if leader_surface is None:
            self._cols = [*range(n_l), n_l]
            self._col_rate = np.r_[np.ones(n_l), joint_f.rate]
        else:
            self._cols = [*range(n_l), n_l + 1, n_l]
            self._col_rate = np.r_[np.ones(n_l), joint_f.rate, self._leader_rate]
        self.model = model
        self.data = model.createData()  # for the callers' own Pinocchio calls
        self.chain = compiled_chain(model)  # the kernel's copy (it pickles itself)
        self._frames = (int(self._tool), int(self._object), int(self._target))
        self._q = np.zeros(model.nq)

    def place_follower(self, surface: GraspSurface) -> None:
        """Put the follower's grasp joint on a new path of the same kind.

        For a path that changes between steps (a Case 2 support line follows gravity in
        object coordinates, :mod:`~dualarm_qp.task.contact`): the joint's placement
        ``P`` and the target's ``C`` are replaced, the model is otherwise unchanged.

        Raises
        ------
        InvalidInputError
            The new path's joint is of another kind or axis.
        """
        joint = surface.slide_joint()
        if (joint.kind, joint.axis) != self._follower_kind:
            raise InvalidInputError(
                f"the follower's grasp joint is {self._follower_kind[0]} along "
                f"{self._follower_kind[1]}; a {joint.kind} joint along {joint.axis} cannot "
                "replace it")
        model, chain = self.model, self.chain
        set_joint_placement(model, chain, self._follower_joint,
                            self._follower_at * _se3(joint.placement))
        set_frame_placement(model, chain, self._target, _se3(joint.child))
        self._follower_rate = joint.rate
        self._col_rate[self.n_l] = joint.rate

    @property
    def columns(self) -> tuple[list[int], FloatArray]:
        """The chain's column of each of ``[q_l, sigma_f, (sigma_l)]`` and its rate.

        Column ``j`` of the decision-order Jacobians (:meth:`kinematics`) is the chain's
        column ``cols[j]`` times ``rate[j]`` (1 for a joint; the grasp joint's units per
        metre for a grasp). The rates are the model's own array: a support re-placing
        the follower's grasp joint (:meth:`place_follower`) updates it.
        """
        return self._cols, self._col_rate

    @property
    def frames(self) -> tuple[int, int, int]:
        """The model's tool, object and target frame indices (the order of :meth:`kinematics`)."""
        return self._frames

    def configuration(self, q_l: FloatArray, sigma_f: float, sigma_l: float = 0.0
                      ) -> FloatArray:
        """Return the model's joints at ``(q_l [rad], sigma_f [m], sigma_l [m])``.

        In Pinocchio's order; a buffer of the model, overwritten by the next call.
        """
        q = self._q
        n_l = self.n_l
        q[:n_l] = q_l
        if self.n_grasp == 2:
            q[n_l] = self._leader_rate * sigma_l
            q[n_l + 1] = self._follower_rate * sigma_f
        else:
            q[n_l] = self._follower_rate * sigma_f
        return q

    def kinematics(self, T: FloatArray, J: FloatArray) -> CarryKinematics:
        """Return the kinematics from the chain's poses ``T`` (12, 4) and Jacobians ``J`` (18, nq).

        ``T`` and ``J`` hold the tool's, the object's and the target's pose and Jacobian
        (:attr:`frames`' order) at :meth:`configuration`'s joints; the Jacobians' grasp
        columns are put in decision order and scaled to sliding speeds here.
        """
        n_l = self.n_l
        J_tool = J[0:6, :n_l]
        J_object = J[6:12]
        J_target = J[12:18]
        if self.n_grasp == 2:  # Pinocchio's order [q_l, leader, follower] -> [q_l, f, l]
            cols, rate = self._cols, self._col_rate
            J_object = J_object[:, cols] * rate
            J_target = J_target[:, cols] * rate
        else:  # already in decision order: only the grasp column is scaled (a fresh array)
            J_object[:, n_l] *= self._follower_rate
            J_target[:, n_l] *= self._follower_rate
        return CarryKinematics(T[0:4], J_tool, T[4:8], J_object, T[8:12], J_target)

    def update(self, q_l: FloatArray, sigma_f: float, sigma_l: float = 0.0) -> CarryKinematics:
        """Compute every pose and Jacobian at ``(q_l [rad], sigma_f [m], sigma_l [m])``."""
        q = self.configuration(q_l, sigma_f, sigma_l)
        T = np.empty((12, 4))
        J = np.empty((18, q.shape[0]))
        self.chain.compute(q, self._frames, self._frames, T, J)
        return self.kinematics(T, J)


__all__ = ["CarryKinematics", "CarryModel"]
