"""What one controller step gives: the command (:class:`ControlOutput`) and its timing."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..solvers.base import Status, StepSolution
from ..step.build import StepBuild

FloatArray = NDArray[np.float64]


@dataclass(slots=True)
class StepTimes:
    """Wall-clock split of one controller step [s].

    ``kinematics`` holds both arms' and the carried object's poses, Jacobians and
    smallest singular values; ``assembly``, ``solve`` and ``verify`` the step problem.
    """

    kinematics: float
    assembly: float
    solve: float
    verify: float

    @property
    def total(self) -> float:
        """Whole controller step [s]."""
        return self.kinematics + self.assembly + self.solve + self.verify


@dataclass(slots=True)
class ControlOutput:
    """What one controller step commands.

    Attributes
    ----------
    ql_dot : ndarray, shape (n_l,)
        Leader joint rates [rad/s] (already scaled when the task was slowed).
    qf_dot : ndarray, shape (n_f,)
        Follower joint rates [rad/s].
    m : float
        Follower grasp sliding speed [m/s].
    m_leader : float
        Leader grasp sliding speed [m/s] (0 when the leader grasps rigidly).
    scale : float
        Path-time rate of this step: the path advances by ``scale * dt`` (1.0 = full
        speed): the ``scale_max`` asked for times the solver's task scale.
    status : Status
        Solver status, or RECOVERING when a variable started outside its range and the
        solver met the bounds that pull it back.
    solution : StepSolution
        The verified solver output (``extras["fallback"]`` when the step was solved by
        the fallback solver after the configured one failed).
    build : StepBuild
        The step problem and every quantity computed on the way (errors, kinematics).
    times : StepTimes
        Timing split of the step.
    applied : bool
        Whether the command is meant to be applied. True for every usable status,
        and for a bound VIOLATION of a method that ignores bounds by design (the
        paper's reference step) whose equality holds; False otherwise (the rates are
        then zero).
    """

    ql_dot: FloatArray
    qf_dot: FloatArray
    m: float
    m_leader: float
    scale: float
    status: Status
    solution: StepSolution
    build: StepBuild
    times: StepTimes
    applied: bool

    @property
    def leader_error(self) -> FloatArray:
        """Object pose error to ``D(t)`` [m, rad] (the leader's tracking error)."""
        return self.build.leader_error

    @property
    def sigma_min(self) -> tuple[float, float]:
        """Smallest singular value of the leader's and the follower's tool Jacobian."""
        return self.build.sigma_min

    @property
    def fallback(self) -> bool:
        """Whether the fallback solver produced this step's command."""
        return "fallback" in self.solution.extras


__all__ = ["ControlOutput", "StepTimes"]
