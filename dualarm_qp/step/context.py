"""What every part of one step reads: the state, its kinematics (computed once) and dt.

The builder (:class:`~dualarm_qp.step.build.StepBuilder`) computes the kinematics of
both arms and of the carried object once per step and hands this context to every task,
cost term and limit; none of them computes kinematics of its own.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from .._compiled import kernel
from ..task.carry import CarryKinematics
from ..task.scene import DualArmTask
from ..task.surfaces import GraspSurface
from .layout import Layout
from .state import DualArmState

FloatArray = NDArray[np.float64]


class ArmKinematics:
    """One arm's model at this step, its kinematics already computed.

    For limits that need more than the tools' poses (the links of an arm, for
    collisions): the builder computed the forward kinematics, the joint Jacobians and
    every frame's pose once, in the compiled kernel (one call per arm); these methods read
    them. The leader's model is the carried-object model (the leader's joints first, then
    the sliding grasps); the follower's is the arm's.

    Parameters
    ----------
    model : pinocchio.Model
        The model (its frame indices are those the methods take).
    data : pinocchio.Data
        A data of ``model``, filled at this step's joints when :attr:`data` is read.
    n_joints : int
        The arm's joints (the first columns of its Jacobians).
    chain : dualarm_qp._kernel.Chain
        The kernel's copy of ``model`` (:mod:`dualarm_qp.kinematics.compiled`), which the
        builder updates each step.
    """

    __slots__ = ("_chain", "_data", "_filled", "model", "n_joints")

    def __init__(self, model: Any, data: Any, n_joints: int, chain: Any) -> None:
        self.model = model
        self.n_joints = n_joints
        self._data = data
        self._chain = chain
        self._filled = -1

    @property
    def data(self) -> Any:
        """``pinocchio.Data`` at this step's joints, for a limit's own Pinocchio calls.

        Filled (forward kinematics, joint Jacobians, frame placements) on first use in a
        step: the step itself never needs it. Valid during this step only.
        """
        chain = self._chain
        if self._filled != chain.updates:
            pin.computeJointJacobians(self.model, self._data, chain.q)
            pin.updateFramePlacements(self.model, self._data)
            self._filled = chain.updates
        return self._data

    @property
    def chain(self) -> Any:
        """The kernel's chain (``dualarm_qp._kernel.Chain``), at this step's joints."""
        return self._chain

    def frame_pose(self, frame: int) -> FloatArray:
        """World pose (4, 4) [m] of the model's frame ``frame``."""
        T = np.empty((4, 4))
        self._chain.frame_poses((frame,), T)
        return T

    def frame_poses(self, frames: Sequence[int]) -> FloatArray:
        """World poses (k, 4, 4) [m] of the model's frames ``frames`` (one kernel call)."""
        T = np.empty((len(frames), 4, 4))
        self._chain.frame_poses(frames, T.reshape(-1, 4))
        return T

    def frame_jacobian(self, frame: int) -> FloatArray:
        """Jacobian (6, n_joints) of frame ``frame``'s origin, world axes ``[v; w]``."""
        J = np.empty((6, self._chain.nq))
        self._chain.frame_jacobian(frame, J)
        return J[:, :self.n_joints]

    def point_jacobian(self, frame: int, point: FloatArray) -> FloatArray:
        """Jacobian (3, n_joints) of the world point ``point`` [m] fixed to frame ``frame``."""
        J = self.frame_jacobian(frame)
        r = point - self.frame_pose(frame)[:3, 3]
        return J[:3] - pin.skew(r) @ J[3:]


class StepContext:
    """The step's state and kinematics: what every part reads.

    The kernel's loop computes the kinematics once, before it asks any part; this object
    reads them from the kernel's context of the step (``kernel_context``, numpy views
    of the kernel's arrays), with the state and the task the step was built from.
    Valid during its step: the arms' kinematics (``leader_arm``, ``follower_arm``) are
    those of the latest step.

    Attributes
    ----------
    state : DualArmState
        The measured state (joints [rad], grasp coordinates [m], path time [s]).
    task : DualArmTask
        Arms, object and path.
    layout : Layout
        The slices of the decision vector.
    leader_arm, follower_arm : ArmKinematics
        The arms' models and kinematics at this step (their links, for limits that need
        them).
    kernel_context : kernel.Context
        The kernel's context of the step (what the compiled parts read).
    x_applied_prev : ndarray or None
        The command applied before the last one [rad/s, m/s] (what jerk limits measure
        the step from, with :attr:`x_applied`); None: the same as :attr:`x_applied`.
    """

    __slots__ = ("_out", "_surfaces", "follower_arm", "kernel_context", "layout", "leader_arm",
                 "state", "task", "x_applied_prev")

    def __init__(self, out: Any, state: DualArmState, task: DualArmTask, layout: Layout,
                 surfaces: tuple[GraspSurface, ...] | Callable[[], tuple[GraspSurface, ...]],
                 leader_arm: ArmKinematics, follower_arm: ArmKinematics) -> None:
        self._out = out
        self.kernel_context = out.context
        self.state = state
        self.task = task
        self.layout = layout
        self._surfaces = surfaces
        self.leader_arm = leader_arm
        self.follower_arm = follower_arm
        self.x_applied_prev: FloatArray | None = None

    @property
    def surfaces(self) -> tuple[GraspSurface, ...]:
        """The grasps' paths at this step, the follower's first.

        A Case 2 support line follows gravity from step to step: the step's line is made
        when first read (``surfaces`` given as a function).
        """
        surfaces = self._surfaces
        if callable(surfaces):
            surfaces = self._surfaces = surfaces()
        return surfaces

    @property
    def dt(self) -> float:
        """Sampling interval [s]."""
        return float(self.kernel_context.dt)

    @property
    def scale_max(self) -> float:
        """Share of the path's feed-forward asked for (1: full speed)."""
        return float(self.kernel_context.scale_max)

    @property
    def carry(self) -> CarryKinematics:
        """Poses and Jacobians of the leader's tool, the object and the follower's target.

        World frame, ``[v; w]``, columns in decision order over the leader's joints and
        the grasps.
        """
        k = self.kernel_context
        return CarryKinematics(k.T_tool, k.J_tool, k.T_object, k.J_object, k.T_target,
                               k.J_target)

    @property
    def T_f(self) -> FloatArray:
        """The follower's tool pose (4, 4) [m]."""
        return np.asarray(self.kernel_context.T_f)

    @property
    def J_f(self) -> FloatArray:
        """The follower's tool Jacobian (6, n_f), world axes ``[v; w]``."""
        return np.asarray(self.kernel_context.J_f)

    @property
    def positions(self) -> FloatArray:
        """What the decision variables are rates of: joints [rad], grasp coordinates [m]."""
        return np.asarray(self.kernel_context.positions)

    @property
    def rate_lo(self) -> FloatArray:
        """Rates [rad/s, m/s] to each variable's lower range end in one sample.

        Eqs. 30-36; ``-inf`` for an unbounded range; ``> 0``: the variable is below its
        range.
        """
        return np.asarray(self.kernel_context.rate_lo)

    @property
    def rate_hi(self) -> FloatArray:
        """Rates [rad/s, m/s] to each variable's upper range end (``< 0``: above it)."""
        return np.asarray(self.kernel_context.rate_hi)

    @property
    def x_applied(self) -> FloatArray:
        """The last command applied [rad/s, m/s] (zero from rest).

        What acceleration limits measure the step from; not the solver's warm start.
        """
        return np.asarray(self.kernel_context.x_applied)

    @property
    def leader_error(self) -> FloatArray:
        """``[dp; dw]`` from the object frame to ``D(t)`` [m, rad]."""
        return np.asarray(self.kernel_context.leader_error)

    @property
    def closure_error(self) -> FloatArray:
        """``[dp; dw]`` from the follower's tool to its target [m, rad]."""
        return np.asarray(self.kernel_context.closure_error)

    @property
    def sigma_min(self) -> tuple[float, float]:
        """Smallest singular value of the leader's and the follower's tool Jacobian.

        Computed by the kernel when first asked in a step (about 6 us for both, a tenth
        of a step): a loop that never reads them does not pay for them.
        """
        sv: tuple[float, float] = self._out.sigma_min()
        return sv

    @property
    def outside(self) -> NDArray[np.bool_]:
        """Variables outside their range (they recover: never further out)."""
        return (self.rate_lo > 0.0) | (self.rate_hi < 0.0)


def smallest_singular_values(J_leader: FloatArray, J_follower: FloatArray
                             ) -> tuple[float, float]:
    """Smallest singular value of the leader's and the follower's tool Jacobian.

    One kernel call for both (a one-sided Jacobi on each Jacobian's rows); 0 for a
    Jacobian with fewer columns than rows, NaN for one that holds NaN or infinity.
    """
    sv = kernel.smallest_singular_values(J_leader, J_follower)
    return sv.leader, sv.follower


__all__ = ["ArmKinematics", "StepContext", "smallest_singular_values"]
