"""The position-level corrections after a step, for the paper's methods only.

Euler integration leaves a closure and tracking error of second order in ``dt`` per
step, which the controller's feedback terms remove over the following steps, inside the
step's limits. The paper's methods, which ignore limits, may also correct the joints
after the step: the Sec. 3.3 re-resolution of the hand orientation on a curved path
(``reresolve_orientation``) and a drift projection (``project``: a few Gauss-Newton
iterations putting the leader on ``D(path time) H1^-1`` and the follower on the grasp).
A solver that claims hard limits refuses both: an unbounded correction after the step
would break them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from ..errors import InvalidInputError
from ..kinematics.arm import SerialArm
from ..kinematics.ik import ik_dls
from ..solvers._affine import factor
from ..step.state import DualArmState
from .controller import DualArmController
from .plant import Plant

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class Corrected:
    """A state after the corrections, and what they did.

    Attributes
    ----------
    state : DualArmState
        The corrected state.
    closure_before : tuple of float
        The grasp closure error before the corrections ``(position [m], rotation [rad])``.
    moved : tuple of float
        The largest joint change of the leader and of the follower [rad].
    failures : int
        Projections that did not converge (0, 1 or 2).
    """

    state: DualArmState
    closure_before: tuple[float, float]
    moved: tuple[float, float]
    failures: int


@dataclass(frozen=True)
class Corrections:
    """Which position-level corrections run after each step.

    Attributes
    ----------
    reresolve_orientation : bool
        Apply the Sec. 3.3 re-resolution of the follower's hand orientation.
    project : bool
        Apply the drift projection of both arms.
    """

    reresolve_orientation: bool
    project: bool

    @classmethod
    def chosen(cls, controller: DualArmController, initial: DualArmState,
               reresolve_orientation: bool | None, project: bool | None,
               plant: Plant | None) -> Corrections:
        """Return the corrections asked for, or the defaults for the controller's solver.

        Defaults: the re-resolution for the paper's methods when the path is curved and
        the controller freezes the orientation; the projection for the paper's methods;
        neither with a plant (they would move a state that is measured, not commanded).

        Raises
        ------
        InvalidInputError
            A correction asked for a solver that claims hard limits.
        """
        surface = controller.task.surface
        hard = controller.hard_bounds
        curved = bool(getattr(surface, "curved", False)) or float(
            np.linalg.norm(surface.angular_rate(float(initial.sigma)))) > 0.0
        if reresolve_orientation is None:
            reresolve_orientation = (not hard and curved and plant is None
                                     and not controller.options.exact_orientation)
        if project is None:
            project = not hard and plant is None
        if hard and (project or reresolve_orientation):
            raise InvalidInputError(
                f"solver '{controller.solver.name}' keeps hard limits: the position-level "
                "corrections (projection, re-resolution) are unbounded and would break "
                "them; its drift is corrected through the step's feedback term")
        return cls(reresolve_orientation, project)

    @property
    def any(self) -> bool:
        """Whether any correction runs."""
        return self.reresolve_orientation or self.project

    def apply(self, controller: DualArmController, state: DualArmState) -> Corrected:
        """Return ``state`` corrected (call only when :attr:`any`)."""
        task = controller.task
        tau, q_l, q_f = state.t, state.q_l, state.q_f
        sigma, sigma_l = state.sigma, state.sigma_leader
        before = task.closure_error(q_l, q_f, sigma, sigma_l)
        q_l0, q_f0 = q_l, q_f
        failures = 0
        if self.reresolve_orientation:
            q_f = reresolve(controller, q_l, q_f, sigma, sigma_l)
        if self.project:
            q_l, ok_l = project_onto(task.leader, task.leader_target(tau, sigma_l), q_l)
            q_f, ok_f = project_onto(task.follower, task.follower_target(q_l, sigma, sigma_l),
                                     q_f)
            failures = (not ok_l) + (not ok_f)
        moved = (float(np.abs(q_l - q_l0).max(initial=0.0)),
                 float(np.abs(q_f - q_f0).max(initial=0.0)))
        return Corrected(DualArmState(tau, q_l, q_f, sigma, sigma_l), before, moved, failures)


def project_onto(arm: SerialArm, T_target: FloatArray, q: FloatArray
                 ) -> tuple[FloatArray, bool]:
    """Move ``q`` onto ``T_target`` by damped Gauss-Newton from the integrated guess.

    Only for the paper's methods, which ignore limits. Returns the corrected joints
    (never worse than ``q``: only steps that lower the error are taken) and whether the
    correction converged to 1e-9 m and rad.
    """
    res = ik_dls(arm, T_target, q, tol_pos=1e-12, tol_rot=1e-12, max_iter=5,
                 respect_limits=False, raise_on_failure=False)
    return res.q, res.position_error <= 1e-9 and res.rotation_error <= 1e-9


def reresolve(controller: DualArmController, q_l: FloatArray, q_f: FloatArray,
              sigma: float, sigma_l: float) -> FloatArray:
    """Sec. 3.3: turn the follower's hand to the grasp frame at the new ``sigma``."""
    task = controller.task
    T_target = task.follower_target(q_l, sigma, sigma_l)
    T_f, J = task.follower.fk_jacobian(q_f)
    dw = pin.log3(T_target[:3, :3] @ T_f[:3, :3].T)
    twist = np.concatenate((np.zeros(3), dw))
    dq = factor(J).solve(twist)  # rank decided at RANK_RTOL, as every step's
    return q_f + dq


__all__ = ["Corrected", "Corrections", "project_onto", "reresolve"]
