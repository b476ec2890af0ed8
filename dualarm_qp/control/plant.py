"""What the rollout drives: by default the model itself, or a plant that measures.

Without a plant, :func:`~dualarm_qp.control.rollout.rollout` integrates each command
exactly (explicit Euler, :meth:`DualArmState.advanced
<dualarm_qp.step.state.DualArmState.advanced>`): the measured state is the commanded
one. A :class:`Plant` takes the command instead and hands back what it measured after
``dt``, e.g. the MuJoCo simulation of :mod:`dualarm_qp.physics.plant`.

With a plant, a tracking or closure error of a measured state is the plan's own only
when the command, followed exactly, would have left it too (:func:`planned_errors`);
otherwise the plant did not follow the command (:func:`not_followed`), and the plan's
kinematics are not blamed for it.
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING, Protocol

import numpy as np
import pinocchio as pin

from ..step.state import Command, DualArmState
from ..task.scene import DualArmTask

if TYPE_CHECKING:
    from .failure import Failure

#: What :func:`not_followed` appends to a failure's message (after ``"; "``).
NOT_FOLLOWED = "the plant did not follow the command"


class Plant(Protocol):
    """A plant the rollout drives at the controller's ``dt``."""

    def reset(self, state: DualArmState, dt: float) -> None:
        """Put the plant at ``state`` (at rest) before the first sample; ``dt`` [s]."""

    def advance(self, state: DualArmState, command: Command, dt: float) -> DualArmState:
        """Apply ``command`` for ``dt`` seconds from ``state``; return the measured state.

        The returned path time is ``state.t + dt * command.scale`` (the path time is the
        controller's, not measured).
        """


def planned_errors(task: DualArmTask, state: DualArmState, command: Command, dt: float
                   ) -> dict[str, tuple[float, float]]:
    """Return the errors ``command`` leaves after ``dt`` when followed exactly (the plan's).

    Returns
    -------
    dict
        ``"closure"`` and ``"tracking"`` (the leader's): ``(position [m], rotation
        [rad])`` at the state the command reaches by explicit Euler.
    """
    nxt = state.advanced(command, dt)
    T = task.leader.fk(nxt.q_l)
    target = task.leader_target(nxt.t, nxt.sigma_leader)
    return {"closure": task.closure_error(nxt.q_l, nxt.q_f, nxt.sigma, nxt.sigma_leader),
            "tracking": (float(np.linalg.norm(target[:3, 3] - T[:3, 3])),
                         float(np.linalg.norm(pin.log3(target[:3, :3] @ T[:3, :3].T))))}


def not_followed(failure: Failure, planned: dict[str, tuple[float, float]],
                 tolerance: tuple[float, float]) -> Failure | None:
    """``failure`` told as the plant's, when the plan's own error was within ``tolerance``.

    Parameters
    ----------
    failure : Failure
        A ``closure`` or ``tracking`` failure at a measured state.
    planned : dict
        :func:`planned_errors` of the command that led to that state.
    tolerance : tuple of float
        The criterion's tolerance ``(position [m], rotation [rad])``.

    Returns
    -------
    Failure or None
        None when the plan's own error also broke the tolerance (then the plan is to
        blame, and the failure is explained from its kinematics).
    """
    pos, rot = planned[failure.criterion]
    if pos > tolerance[0] or rot > tolerance[1]:
        return None
    return dataclasses.replace(
        failure, message=f"{failure.message}; {NOT_FOLLOWED}: followed exactly, it "
        f"would have left {pos:.3g} m, {rot:.3g} rad here, within "
        "the tolerance, so what grew is the plant's own error (e.g. its servos' lag or "
        "oscillation), not the plan's")


__all__ = ["NOT_FOLLOWED", "Plant", "not_followed", "planned_errors"]
