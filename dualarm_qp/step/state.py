"""The measured state of the pair, and the command a step gives it."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class DualArmState:
    """Measured state of the pair at one instant.

    Attributes
    ----------
    t : float
        Path time [s] at which the desired object pose D(t) is read.
    q_l, q_f : ndarray, shape (n_l,), (n_f,)
        Leader and follower joints [rad].
    sigma : float
        Follower grasp coordinate along its sliding path [m].
    sigma_leader : float
        Leader grasp coordinate along its sliding path [m]; ignored (0) when the leader
        grasps rigidly.
    """

    t: float
    q_l: FloatArray
    q_f: FloatArray
    sigma: float
    sigma_leader: float = 0.0

    def advanced(self, command: Command, dt: float) -> DualArmState:
        """Return the state after applying ``command`` for ``dt`` seconds (explicit Euler).

        Joints move by ``dt`` times their rates, each grasp by ``dt`` times its sliding
        speed, and the path time by ``dt`` times the command's ``scale`` (the path slows
        when the task was scaled). ``command`` is a controller step's output
        (:class:`~dualarm_qp.control.controller.ControlOutput`) or anything with the
        same rates.
        """
        return DualArmState(self.t + dt * command.scale, self.q_l + dt * command.ql_dot,
                            self.q_f + dt * command.qf_dot, self.sigma + dt * command.m,
                            self.sigma_leader + dt * command.m_leader)


class Command(Protocol):
    """The rates one controller step commands (what :meth:`DualArmState.advanced` reads).

    Attributes
    ----------
    ql_dot, qf_dot : ndarray
        Joint rates of the leader and the follower [rad/s].
    m, m_leader : float
        Sliding speeds of the follower's and the leader's grasp [m/s].
    scale : float
        Path-time rate of the step (1: full speed).
    """

    @property
    def ql_dot(self) -> FloatArray:
        """Leader joint rates [rad/s]."""

    @property
    def qf_dot(self) -> FloatArray:
        """Follower joint rates [rad/s]."""

    @property
    def m(self) -> float:
        """Follower grasp sliding speed [m/s]."""

    @property
    def m_leader(self) -> float:
        """Leader grasp sliding speed [m/s]."""

    @property
    def scale(self) -> float:
        """Path-time rate of the step."""


__all__ = ["Command", "DualArmState"]
