"""What one backend call answered, with the problem it answers and its own residuals.

Every backend sees the step QP in the shifted variable ``y = x - c``
(:mod:`.shifted`); its answer keeps the problem it was asked, so that it gives its point
in ``x`` and says how far that point is from the constraints (as qpsolvers' ``Solution``
does), whatever the backend claimed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ...step.problem import StepProblem
from ..certify import residuals

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class BackendAnswer:
    """What one backend call returned.

    Attributes
    ----------
    problem : StepProblem
        The problem the backend was asked (in ``x``; the backend saw it in ``y = x - c``).
    y : ndarray or None
        The backend's last iterate in ``y`` (None when it returned none).
    solved : bool
        The backend says it met its tolerances.
    infeasible : bool
        The backend says the constraints are inconsistent (primal infeasible).
    status : str
        The backend's status, as text.
    iterations : int or None
        Iterations used, where the backend reports them.
    """

    problem: StepProblem
    y: FloatArray | None
    solved: bool
    infeasible: bool
    status: str
    iterations: int | None = None

    @property
    def x(self) -> FloatArray | None:
        """The backend's point in the step's variables, ``y + c`` (None without one)."""
        return None if self.y is None else self.y + self.problem.center

    def residuals(self) -> tuple[float, float]:
        """Return ``(max |A x - b|, largest violation of a box or a unit-norm row)`` at :attr:`x`.

        Both are infinite when the backend gave no finite point.
        """
        x = self.x
        if x is None or not np.isfinite(x).all():
            return math.inf, math.inf
        return residuals(self.problem, x)

    def primal_residual(self) -> float:
        """Return the larger of the two :meth:`residuals` (0 at a feasible point)."""
        return max(self.residuals())


__all__ = ["BackendAnswer"]
