"""A built step: the problem the builder made and every quantity computed on the way.

:class:`~dualarm_qp.step.build.StepBuilder` makes one per step from the kernel's step
(``kernel.StepOut``); the controller reads its errors, its kinematics and the arms'
smallest singular values (computed by the kernel when first asked).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._compiled import kernel
from ..task.carry import CarryKinematics
from .context import StepContext
from .problem import StepProblem

FloatArray = NDArray[np.float64]


@dataclass(slots=True)
class StepBuild:
    """A built step: the problem and every quantity computed on the way.

    Attributes
    ----------
    problem : StepProblem
        The problem handed to the solver (rows: the object's path, then the closure,
        then any task of the user's).
    parts : kernel.StepOut
        The kernel's step: its context and its problem's pieces, as named fields.
    context : StepContext
        What every part read.
    kinematics_time, assembly_time : float
        Seconds spent in the kinematics and in asking and stacking the parts.
    support_force : float
        Follower push ``h`` [N] of a Case 2 support at this state (NaN for a grasp).
    """

    problem: StepProblem
    parts: Any
    context: StepContext
    kinematics_time: float
    assembly_time: float
    support_force: float = math.nan

    @property
    def recovering(self) -> NDArray[np.bool_]:
        """Variables that start outside their range (the box forces them back)."""
        return np.asarray(self.parts.recovering)

    @property
    def recovers(self) -> bool:
        """Whether any variable starts outside its range."""
        return bool(self.parts.any_recovering)

    @property
    def closure_error(self) -> FloatArray:
        """``[dp; dw]`` from the follower's tool to its target [m, rad]."""
        return np.asarray(self.parts.context.closure_error)

    @property
    def leader_error(self) -> FloatArray:
        """``[dp; dw]`` from the object frame to ``D(t)`` [m, rad]."""
        return np.asarray(self.parts.context.leader_error)

    @property
    def carry(self) -> CarryKinematics:
        """Leader, object and target poses and Jacobians at this state."""
        return self.context.carry

    @property
    def T_f(self) -> FloatArray:
        """Follower tool pose (4, 4) [m]."""
        return np.asarray(self.parts.context.T_f)

    @property
    def J_f(self) -> FloatArray:
        """Follower tool Jacobian (6, n_f)."""
        return np.asarray(self.parts.context.J_f)

    @property
    def sigma_min(self) -> tuple[float, float]:
        """Smallest singular value of the leader's and the follower's tool Jacobian.

        Computed by the kernel when first asked (shared with the context).
        """
        sv: tuple[float, float] = self.parts.sigma_min()
        return sv


def smallest_singular_value(J: FloatArray) -> float:
    """Smallest singular value of the joint Jacobian ``J`` (0 with fewer columns than rows)."""
    return float(kernel.smallest_singular_value(J))


__all__ = ["StepBuild", "smallest_singular_value"]
