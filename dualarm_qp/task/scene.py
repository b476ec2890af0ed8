"""The dual-arm task: two arms, the carried object, the grasps and the path D(t).

Frames (all poses are 4x4 homogeneous matrices, metres):

- ``T_world_leader = leader.fk(q_l)``: the leader's tool (the paper's T_B^n(q^l));
- ``H1 = T_leader_object``: the object frame in the leader's tool frame (Eq. 14),
  constant when the leader grasps rigidly; when the leader's grasp slides too (the
  paper's future work) it is ``G_l(sigma_l)^-1``, with ``G_l = leader_surface.pose``;
- ``H2(sigma) = T_object_follower``: the follower's grasp frame on the object surface
  (Eq. 16), a function of the grasp coordinate ``sigma`` [m] along the sliding path;
- the grasp closure (Eq. 15): ``leader.fk(q_l) @ H1 @ H2(sigma) == follower.fk(q_f)``;
- the carried-object model (:mod:`~dualarm_qp.task.carry`) holds every sliding grasp as a
  joint;
- the desired object path ``D(t) = T_world_object(t)`` (Eq. 14).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from .._validate import as_pose
from ..collision.scene import CollisionScene
from ..errors import InvalidInputError
from ..kinematics.arm import SerialArm
from .contact import SupportContact
from .loads import ObjectLoad
from .surfaces import GraspSurface
from .trajectory import Trajectory

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class DualArmTask:
    """Everything that defines a leader-follower carrying task.

    Parameters
    ----------
    leader, follower : SerialArm
        The two arms, each with its base pose in the common world frame.
    H1 : ndarray, shape (4, 4)
        ``T_leader_object``: object frame in the leader's tool frame [m].
    surface : GraspSurface
        The object surface and the follower's sliding path on it.
    trajectory : Trajectory
        Desired object pose ``D(t)`` in the world.
    leader_surface : GraspSurface, optional
        The leader's own sliding path on the object (object coordinates); None (the
        default): the leader grasps rigidly at ``H1``. When given, ``H1`` must be the
        identity: the leader's grasp frame is ``leader_surface.pose(sigma_l)``.
    contact : SupportContact, optional
        None (the default): the follower grasps the object (Case 1) and ``surface`` is
        its fixed path. A :class:`~dualarm_qp.task.contact.SupportContact`: the follower
        only supports it (Case 2); ``surface`` is then the support line at the start,
        and the step builder replaces it by the line for the object's orientation at
        every step (docs/support.md). Needs a rigid leader grasp.
    scene : CollisionScene, optional
        The bodies that may collide (links, object, obstacles) and the pairs checked;
        with ``scene.settings.enabled`` the step keeps them apart
        (:mod:`dualarm_qp.step.limits.collision`), otherwise their clearance is only
        measured. None (the default): no geometry.
    load : ObjectLoad, optional
        The object's mass, mass centre and gravity: given, a run records the wrench each
        hand applies (:mod:`dualarm_qp.control.loads`). None (the default): no load is
        computed. With a support it must agree with ``contact``.
    """

    leader: SerialArm
    follower: SerialArm
    H1: FloatArray
    surface: GraspSurface
    trajectory: Trajectory
    leader_surface: GraspSurface | None = None
    contact: SupportContact | None = None
    scene: CollisionScene | None = None
    load: ObjectLoad | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "H1", as_pose(self.H1, "H1"))
        if not isinstance(self.leader, SerialArm) or not isinstance(self.follower, SerialArm):
            raise InvalidInputError("leader and follower must be SerialArm instances")
        if self.leader_surface is not None and not np.allclose(self.H1, np.eye(4),
                                                               rtol=0.0, atol=1e-12):
            raise InvalidInputError("a sliding leader grasp places the object by its "
                                    "surface: H1 must be the identity")
        if self.contact is not None:
            if not isinstance(self.contact, SupportContact):
                raise InvalidInputError("contact must be None (a grasp) or a SupportContact")
            if self.leader_surface is not None:
                raise InvalidInputError("a supporting follower needs a rigid leader grasp "
                                        "(no leader_surface)")
        if self.load is not None:
            if not isinstance(self.load, ObjectLoad):
                raise InvalidInputError("load must be None or an ObjectLoad")
            c = self.contact
            if c is not None and not (
                    c.mass == self.load.mass and np.array_equal(c.mass_centre,
                                                                self.load.mass_centre)
                    and np.array_equal(c.gravity, self.load.gravity)):
                raise InvalidInputError("the load's mass, mass centre and gravity must be "
                                        "the support's")
        if self.scene is not None:
            if not isinstance(self.scene, CollisionScene):
                raise InvalidInputError("scene must be None or a CollisionScene")
            if self.scene.n_frames != (self.leader.n + 1, self.follower.n + 1):
                raise InvalidInputError(
                    f"the collision scene was built for arms of {self.scene.n_frames[0] - 1} "
                    f"and {self.scene.n_frames[1] - 1} joints, the task's have "
                    f"{self.leader.n} and {self.follower.n}")

    @property
    def n_grasp(self) -> int:
        """Sliding grasps: 1 (the follower's) or 2 (the leader's slides too)."""
        return 1 if self.leader_surface is None else 2

    def H1_at(self, sigma_l: float = 0.0) -> FloatArray:
        """``T_leader_object`` at the leader's grasp coordinate ``sigma_l`` [m]."""
        if self.leader_surface is None:
            return self.H1
        return pin.SE3(self.leader_surface.pose(sigma_l)).inverse().homogeneous

    @property
    def H1_inv(self) -> FloatArray:
        """``T_object_leader`` of a rigid leader grasp."""
        return pin.SE3(self.H1).inverse().homogeneous

    def leader_target(self, t: float, sigma_l: float = 0.0) -> FloatArray:
        """Pose the leader's tool must take for the object to be at ``D(t)``."""
        return self.trajectory.pose(t) @ pin.SE3(self.H1_at(sigma_l)).inverse().homogeneous

    def object_pose(self, q_l: FloatArray, sigma_l: float = 0.0) -> FloatArray:
        """``T_world_object`` carried by the leader at joints ``q_l``."""
        return self.leader.fk(q_l) @ self.H1_at(sigma_l)

    def follower_target(self, q_l: FloatArray, sigma: float, sigma_l: float = 0.0
                        ) -> FloatArray:
        """Pose the follower's tool must take: ``T_l(q_l) H1 H2(sigma)`` (Eq. 15)."""
        return self.object_pose(q_l, sigma_l) @ self.surface.pose(sigma)

    def closure_error(self, q_l: FloatArray, q_f: FloatArray, sigma: float,
                      sigma_l: float = 0.0) -> tuple[float, float]:
        """Grasp closure error ``(position [m], rotation [rad])`` of Eq. 15."""
        T_target = self.follower_target(q_l, sigma, sigma_l)
        T_f = self.follower.fk(q_f)
        dp = float(np.linalg.norm(T_target[:3, 3] - T_f[:3, 3]))
        dw = float(np.linalg.norm(pin.log3(T_target[:3, :3] @ T_f[:3, :3].T)))
        return dp, dw

    def follower_base_from_grasp(self, q_f: FloatArray, sigma: float, t: float) -> FloatArray:
        """Return the base pose that puts the follower's tool on the grasp at time ``t``.

        ``T_world_base_f = D(t) H2(sigma) (T_base_f_tool(q_f))^-1``: how the paper's
        unstated follower base is recovered from Table 2 (see docs/reproduction.md).
        """
        T_base_tool = self.follower.with_base(np.eye(4)).fk(q_f)
        tool_base = pin.SE3(T_base_tool).inverse().homogeneous
        return self.trajectory.pose(t) @ self.surface.pose(sigma) @ tool_base
