"""The step problem: the data one controller step hands to a solver.

A step problem is a value, built once per control step by pure functions
(:mod:`dualarm_qp.step.build`) and handed unchanged to any solver in the registry.
It knows nothing of robots: only the linear algebra of Eqs. 25 and 33-40 of the paper.

Find ``x`` (both arms' joint rates [rad/s] followed by the grasp sliding speeds [m/s],
see :mod:`dualarm_qp.step.build`) that minimises the weighted distance to the centre of
the admissible ranges,

    minimise    (x - center)^T diag(weights) (x - center)          (Eq. 37)
    subject to  A x = b                                             (Eq. 25)
                lower <= x <= upper                                 (Eqs. 33-34)

with the object's path and the grasp closure as the equality rows.
The last ``n_grasp`` variables are grasp sliding speeds; the fixed-grasp method of
Zheng and Luh holds them at zero.
"""

from __future__ import annotations

import math
import operator
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidInputError, NonFiniteError, ShapeError

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class StepProblem:
    """Equality-constrained, box-bounded weighted least-distance problem of one step.

    Parameters
    ----------
    A : ndarray, shape (m, n)
        Equality matrix (Eqs. 14 and 25-27: m = 12 for a controller step).
    b : ndarray, shape (m,)
        Right-hand side [m/s; rad/s], feedback terms included.
    weights : ndarray, shape (n,)
        Diagonal of the positive definite weighting matrix ``S`` (Eq. 37).
    center : ndarray, shape (n,)
        Centre of the admissible ranges ``dqhat_c`` (Eqs. 38-40) [rad/s, m/s].
    lower, upper : ndarray, shape (n,)
        Hard bounds on ``x`` (Eqs. 33-34, intersected with velocity limits).
        ``lower[i] > upper[i]`` is allowed and means that bound ``i`` is empty:
        solvers report the step as infeasible.
    n_grasp : int
        Number of trailing variables that are grasp sliding speeds (default 1).
    x_prev : ndarray, shape (n,), optional
        Solution of the previous step, for warm starts.
    names : tuple of str, optional
        Variable names used in reports (default ``x1..xn``).
    task_scale_max : float
        Largest allowed scale of ``b`` (1.0: the full task). Solvers that scale the
        task search ``s`` in ``[0, task_scale_max]``.
    build_time : float
        Seconds spent building this problem (filled by the builder).
    """

    A: FloatArray
    b: FloatArray
    weights: FloatArray
    center: FloatArray
    lower: FloatArray
    upper: FloatArray
    n_grasp: int = 1
    x_prev: FloatArray | None = None
    names: tuple[str, ...] = field(default=())
    task_scale_max: float = 1.0
    build_time: float = 0.0

    def __post_init__(self) -> None:
        A = np.asarray(self.A, dtype=np.float64)
        if A.ndim != 2:
            raise ShapeError("A", (-1, -1), A.shape)
        m, n = A.shape
        object.__setattr__(self, "A", A)
        for name, shape in (("b", (m,)), ("weights", (n,)), ("center", (n,)),
                            ("lower", (n,)), ("upper", (n,))):
            arr = np.asarray(getattr(self, name), dtype=np.float64)
            if arr.shape != shape:
                raise ShapeError(name, shape, arr.shape)
            object.__setattr__(self, name, arr)
        if self.x_prev is not None:
            xp = np.asarray(self.x_prev, dtype=np.float64)
            if xp.shape != (n,):
                raise ShapeError("x_prev", (n,), xp.shape)
            object.__setattr__(self, "x_prev", xp)
        # One sum per array: NaN and infinity propagate through it; only a sum that is
        # not finite needs the element-wise look (an overflow of huge finite entries
        # passes it).
        for name in ("A", "b", "weights", "center"):
            arr = getattr(self, name)
            if not math.isfinite(float(arr.sum())) and not np.isfinite(arr).all():
                raise NonFiniteError(name)
        # Bounds may be infinite (no limit) but never NaN.
        for name in ("lower", "upper"):
            arr = getattr(self, name)
            if math.isnan(float(arr.sum())) and np.isnan(arr).any():
                raise NonFiniteError(name)
        if n and not float(self.weights.min()) > 0.0:
            raise InvalidInputError("weights must be strictly positive")
        if not 0 <= self.n_grasp <= n:
            raise InvalidInputError(f"n_grasp must be in [0, {n}], got {self.n_grasp}")
        if not self.names:
            object.__setattr__(self, "names", tuple(f"x{i + 1}" for i in range(n)))
        elif len(self.names) != n:
            raise ShapeError("names", (n,), (len(self.names),))

    @property
    def n(self) -> int:
        """Number of variables."""
        return int(self.A.shape[1])

    @property
    def m(self) -> int:
        """Number of equality constraints."""
        return int(self.A.shape[0])

    def objective(self, x: FloatArray) -> float:
        """Value of Eq. 37, ``(x - c)^T S (x - c)``, at ``x``."""
        # Python floats: for a handful of variables cheaper than three numpy calls.
        d = list(map(operator.sub, np.asarray(x, dtype=np.float64).tolist(),
                     self.center.tolist()))
        return float(sum(map(operator.mul, self.weights.tolist(), map(operator.mul, d, d))))

    def empty_bounds(self) -> tuple[str, ...]:
        """Names of the variables whose box is empty (``lower > upper``)."""
        return tuple(self.names[i] for i in np.flatnonzero(self.lower > self.upper))
