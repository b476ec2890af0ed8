"""Look one step ahead: the errors a command leaves after one sample.

The step problem is linear in the rates (Eqs. 14 and 25): it holds the object on its
path and the grasp closed to first order. A step that moves the joints far within one
sample (a fast object, a coarse ``dt``) leaves a second-order error that the linear
step cannot see: the leader leaves its path, the grasp opens. The scale policy slows
the path only for the limits; this module lets the same task scale answer for the
errors too. For a command ``x`` the controller asks :meth:`Lookahead.predict_checked`;
when the errors predicted at the next sample (forward kinematics at ``q + dt x``, the
path at ``t + scale dt``, in one kernel call) pass the budget, it slows the task further
(:class:`~.controller.DualArmController`).

A cheap bound decides first whether the prediction is needed: a chain of revolute
joints whose joints turn by ``dq`` moves its tool off its first-order path by at most
``(sum |dq_i|)^2 L / 2`` [m] and ``(sum |dq_i|)^2 / 2`` [rad], with ``L`` the length of
the chain (the sum of its links). Steps under a tenth of the budget skip the forward
kinematics.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .._compiled import kernel
from .._validate import as_number
from ..errors import NonFiniteError
from ..kinematics.arm import SerialArm
from ..step.build import StepBuild
from ..step.stacking import checked_rates
from ..step.state import DualArmState
from ..task.carry import CarryModel
from ..task.scene import DualArmTask

FloatArray = NDArray[np.float64]

#: Share of the budget under which the bound skips the prediction.
SKIP_SHARE = 0.1


@dataclass(slots=True)
class Predicted:
    """Errors expected one sample after a command.

    Attributes
    ----------
    tracking : tuple of float
        The object's error to ``D(t)`` (position [m], rotation [rad]).
    closure : tuple of float
        The grasp closure error (position [m], rotation [rad]).
    """

    tracking: tuple[float, float]
    closure: tuple[float, float]

    def share(self, budget: tuple[float, float]) -> float:
        """Largest error relative to ``budget`` (above 1: over it)."""
        return max(self.tracking[0] / budget[0], self.tracking[1] / budget[1],
                   self.closure[0] / budget[0], self.closure[1] / budget[1])


def chain_length(arm: SerialArm) -> float:
    """Sum of the link lengths from the arm's first joint to its tool [m]."""
    model = arm.model
    links = sum(float(np.linalg.norm(model.jointPlacements[j].translation))
                for j in range(2, model.njoints))
    return links + float(np.linalg.norm(model.frames[arm.tool_frame_id].placement.translation))


class Lookahead:
    """Predicts the errors a command leaves after one sample.

    Parameters
    ----------
    task : DualArmTask
        Arms, object and path.
    budget : tuple of float
        Largest predicted error (position [m], rotation [rad]) of the leader's tracking
        and of the grasp closure that a step may leave.
    carry : CarryModel
        The step builder's carried-object model (shared: the prediction runs after the
        step's kinematics were read from it, and a Case 2 support line placed on it
        holds for the prediction too).
    n_l, n_f : int
        Joints of the leader and the follower (the slices of the decision vector).
    """

    def __init__(self, task: DualArmTask, budget: tuple[float, float], carry: CarryModel,
                 n_l: int, n_f: int) -> None:
        self.task = task
        self.budget = (float(budget[0]), float(budget[1]))
        self.n_l, self.n_f = n_l, n_f
        self._carry = carry
        self._length = (chain_length(task.leader), chain_length(task.follower))

    def negligible(self, build: StepBuild, x: FloatArray, dt: float) -> bool:
        """Whether the bound alone keeps the command's error under a tenth of the budget.

        The bound of the module docstring, one kernel call (``kernel.negligible``): the
        leader's turn counts with its chain's length plus the lever from its tool to the
        follower's target, and a grasp's travel as a turn of the object's length (a grasp
        sliding on a curved path turns with it; a straight path adds nothing at second
        order but is counted too, cheaply and safely).
        """
        ctx = build.parts.context
        negligible: bool = kernel.negligible(
            x, self.n_l, self.n_f, dt, ctx.T_tool, ctx.T_target, self._length[0],
            self._length[1], self.budget[0], self.budget[1], SKIP_SHARE)
        return negligible

    def predict(self, state: DualArmState, x: FloatArray, scale: float, dt: float
                ) -> Predicted:
        """Errors at the next sample after applying ``x`` for ``dt`` with path rate ``scale``.

        Raises
        ------
        ShapeError, NonFiniteError, InvalidInputError
            Joints of the wrong length or with NaN, ``x`` not ``n`` real numbers, a NaN
            in ``x``, a grasp coordinate that is not a finite number, or a NaN in the
            grasp coordinates ``x`` reaches.
        """
        task = self.task
        # Checked as the controller checks a state: a vector of the wrong length or a NaN
        # is a clear error, never a NaN prediction.
        q_l = task.leader.check_q(state.q_l, "leader joints q_l")
        q_f = task.follower.check_q(state.q_f, "follower joints q_f")
        x = checked_rates(x, "the command x", self.n_l + self.n_f + self._carry.n_grasp)
        sigma = as_number(state.sigma, "sigma")
        sigma_l = as_number(state.sigma_leader, "sigma_leader")
        return self.predict_checked(DualArmState(state.t, q_l, q_f, sigma, sigma_l), x,
                                    scale, dt)

    def predict_checked(self, state: DualArmState, x: FloatArray, scale: float, dt: float
                        ) -> Predicted:
        """:meth:`predict` for a caller that checked its inputs (the controller's step).

        ``state``'s joints are finite float64 arrays of the arms' lengths and its grasp
        coordinates floats; ``x`` is a C-ordered float64 array of the decision's length.
        One kernel call moves the joints and the grasps by ``dt x`` and computes the two
        pose errors there (``kernel.predicted_errors``).

        Raises
        ------
        NonFiniteError
            A NaN or an infinity in ``x`` or in the grasp coordinates it reaches.
        """
        carry, follower = self._carry, self.task.follower
        e = kernel.predicted_errors(
            carry.chain, carry.frames, follower.chain, follower.tool_frame_id, state.q_l,
            state.q_f, state.sigma, state.sigma_leader, x, carry.columns[1], dt,
            self.task.trajectory.pose(state.t + scale * dt))
        if not e.finite:
            raise NonFiniteError("the command x or the grasp coordinates")
        return Predicted((e.tracking_position, e.tracking_rotation),
                         (e.closure_position, e.closure_rotation))


__all__ = ["Lookahead", "Predicted", "chain_length"]
