"""A built step: the problem the builder made and every quantity computed on the way.

:class:`~dualarm_qp.step.build.StepBuilder` makes one per step; the controller reads its
errors, its kinematics and the arms' smallest singular values (computed when first read).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from .._compiled import kernel
from ..task.carry import CarryKinematics
from .context import StepContext, smallest_singular_values
from .problem import StepProblem

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class StepBuild:
    """A built step: the problem and every quantity computed on the way.

    Attributes
    ----------
    problem : StepProblem
        The problem handed to the solver (rows: leader task, then closure).
    recovering : ndarray of bool, shape (n,)
        Variables that start outside their range (the box forces them back).
    recovers : bool
        Whether any does (the kernel says so with the array).
    closure_error : ndarray, shape (6,)
        ``[dp; dw]`` from the follower's tool to its target [m, rad].
    leader_error : ndarray, shape (6,)
        ``[dp; dw]`` from the object frame to ``D(t)`` [m, rad].
    carry : CarryKinematics
        Leader, object and target poses and Jacobians at this state.
    T_f, J_f : ndarray
        Follower tool pose (4, 4) and Jacobian (6, n_f).
    kinematics_time, assembly_time : float
        Seconds spent in the kinematics and in assembling the problem.
    support_force : float
        Follower push ``h`` [N] of a Case 2 support at this state (NaN for a grasp).
    context : StepContext or None
        What the parts read. When no limit read it during the build, the builder
        gives a function that makes it, and it is made when first read.
    sigma_min : tuple of float
        Smallest singular value of the leader's and the follower's tool Jacobian
        (computed when first read, once, and shared with the context).
    """

    problem: StepProblem
    recovering: NDArray[np.bool_]
    closure_error: FloatArray
    leader_error: FloatArray
    carry: CarryKinematics
    T_f: FloatArray
    J_f: FloatArray
    kinematics_time: float
    assembly_time: float
    support_force: float = math.nan
    _context: StepContext | Callable[[tuple[float, float] | None], StepContext] | None = (
        field(default=None, repr=False, compare=False))
    _recovers: bool | None = field(default=None, init=False, repr=False, compare=False)
    _sigma_min: tuple[float, float] | None = field(default=None, init=False, repr=False,
                                                   compare=False)

    @property
    def context(self) -> StepContext | None:
        """What the parts read (made now if no limit read it during the build)."""
        ctx = self._context
        if ctx is None or isinstance(ctx, StepContext):
            return ctx
        made = ctx(self._sigma_min)  # the singular values, if read, carry over
        object.__setattr__(self, "_context", made)  # a cache, on a frozen build
        return made

    @property
    def recovers(self) -> bool:
        """Whether some variable starts outside its range (``recovering.any()``)."""
        flag = self._recovers  # the kernel's, set with the array it made
        return bool(self.recovering.any()) if flag is None else flag

    @property
    def sigma_min(self) -> tuple[float, float]:
        """Smallest singular value of the leader's and the follower's tool Jacobian."""
        sv = self._sigma_min
        if sv is None:
            ctx = self._context
            sv = (ctx.sigma_min if isinstance(ctx, StepContext)  # computed once
                  else smallest_singular_values(self.carry.J_tool, self.J_f))
            object.__setattr__(self, "_sigma_min", sv)
        return sv


def smallest_singular_value(J: FloatArray) -> float:
    """Smallest singular value of the joint Jacobian ``J`` (0 with fewer columns than rows)."""
    return float(kernel.smallest_singular_value(J))


__all__ = ["StepBuild", "smallest_singular_value"]
