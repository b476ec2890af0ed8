"""The parts a step is stacked from: equality tasks, cost terms and limits.

A step problem (:class:`~dualarm_qp.step.problem.StepProblem`) is not written out by
hand: :class:`~dualarm_qp.step.build.StepBuilder` stacks small parts, each of which
reads the step's context (:class:`~dualarm_qp.step.context.StepContext`: the state,
its kinematics computed once, ``dt``) and returns its piece:

* a **task** gives equality rows ``A_i x = b_i`` (the object follows ``D(t)``; the
  grasp stays closed);
* a **cost term** gives a weighted distance ``(x - c_i)^T W_i (x - c_i)`` (the paper's
  centring, Eqs. 37-40);
* a **limit** gives boxes on named variables and/or rows ``G x <= h`` with a name per
  row (joint range and speed, grasp range and speed, acceleration, a user's wall, the
  collision distances).

Adding a limit is one class with a ``name``, a ``gives_rows`` flag (whether it gives
general rows, which some solvers cannot take) and one method, ``constraint(ctx)``;
see ``docs/api.md`` and ``examples/custom_limit.py``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

if TYPE_CHECKING:
    from .context import StepContext

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class Equality:
    """Equality rows ``A x = b`` of a task.

    Attributes
    ----------
    A : ndarray, shape (k, n)
        Rows over the whole decision vector.
    b : ndarray, shape (k,)
        Right-hand side (the task scale multiplies it).
    names : tuple of str
        One name per row.
    """

    A: FloatArray
    b: FloatArray
    names: tuple[str, ...]


@dataclass(frozen=True, slots=True)
class Quadratic:
    """A cost term ``(x - center)^T W (x - center)``.

    Attributes
    ----------
    weights : ndarray, shape (n,) or (n, n)
        ``W``: its diagonal, or the whole symmetric positive (semi)definite matrix.
    center : ndarray, shape (n,)
        Where the term is zero [rad/s, m/s].
    """

    weights: FloatArray
    center: FloatArray


@dataclass(frozen=True, slots=True)
class Constraint:
    """What a limit asks of ``x``: boxes and/or rows.

    Attributes
    ----------
    lower, upper : ndarray, shape (n,), optional
        Bounds on each variable (``-inf`` / ``inf`` where the limit says nothing); None
        for no box at all.
    G : ndarray, shape (p, n), optional
        Rows ``G x <= h``; None for no rows.
    h : ndarray, shape (p,), optional
        Their right-hand sides (``inf`` for a row that does not bind).
    row_names : tuple of str
        One name per row (``"wall"``, ``"qf3 - obstacle pillar"``).
    """

    lower: FloatArray | None = None
    upper: FloatArray | None = None
    G: FloatArray | None = None
    h: FloatArray | None = None
    row_names: tuple[str, ...] = ()


@runtime_checkable
class Task(Protocol):
    """An equality task of the step."""

    name: str

    def equality(self, ctx: StepContext) -> Equality:
        """Return the task's rows at this step."""
        ...


@runtime_checkable
class CostTerm(Protocol):
    """A term of the step's cost."""

    name: str

    def quadratic(self, ctx: StepContext) -> Quadratic:
        """Return the term's weights and centre at this step."""
        ...


@runtime_checkable
class Limit(Protocol):
    """A limit of the step: boxes and/or rows.

    Attributes
    ----------
    name : str
        How messages and the pairing check name it (``"joint speed"``, ``"wall"``).
    gives_rows : bool
        Whether :meth:`constraint` may give general rows ``G x <= h`` (a solver that
        takes boxes only is refused for a step with such a limit).
    """

    name: str
    gives_rows: bool

    def constraint(self, ctx: StepContext) -> Constraint:
        """Return the limit's boxes and rows at this step."""
        ...


__all__ = ["Constraint", "CostTerm", "Equality", "Limit", "Quadratic", "Task"]
