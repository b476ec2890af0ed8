"""The parts a step is made of: tasks, cost terms and limits, and what each gives.

A step problem (:class:`~dualarm_qp.step.problem.StepProblem`) is not written out by
hand: each step, one loop (:class:`~dualarm_qp.step.build.StepBuilder`, in the compiled
kernel) makes the step's context (:class:`~dualarm_qp.step.context.StepContext`: the
state, its kinematics computed once, ``dt``), asks every part in turn for its piece and
stacks the pieces:

* a **task** gives rows ``A x = b`` (:class:`Equality`): an equality of the step (the
  object follows ``D(t)``; the grasp stays closed) or, with a ``weight``, the cost term
  ``weight |A x - b|^2`` (a posture to hold in the null space of the equalities);
* a **cost term** gives a weighted distance ``(x - c)^T W (x - c)`` (:class:`Quadratic`:
  the paper's centring, Eqs. 37-40); the terms and the weighted tasks are summed;
* a **limit** gives boxes on named variables and/or rows ``G x <= h`` with a name per
  row (:class:`Constraint`: joint range and speed, grasp range and speed, acceleration,
  the collision distances, a wall of yours).

Every part is asked through the same door. The library's own are compiled: objects of
the kernel's part classes (``kernel.Task``, ``kernel.CostTerm``, ``kernel.Limit``), each
with one method the kernel's loop calls. A part of yours is any object of the protocols
below: the loop asks it in turn, in its place among the others (the builder wraps it in
a kernel part, :mod:`.python_parts`). See ``docs/api.md``, ``examples/custom_limit.py``
and ``examples/custom_task.py``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

if TYPE_CHECKING:
    from .context import StepContext

FloatArray = NDArray[np.float64]


@dataclass(slots=True)
class Equality:
    """Rows ``A x = b`` of a task.

    Attributes
    ----------
    A : ndarray, shape (k, n)
        Rows over the whole decision vector.
    b : ndarray, shape (k,)
        Right-hand side [m/s, rad/s] (the policy's task scale multiplies it).
    names : tuple of str
        One name per row.
    """

    A: Any
    b: Any
    names: tuple[str, ...] = ()


@dataclass(slots=True)
class Quadratic:
    """A cost term ``(x - center)^T W (x - center)``.

    Attributes
    ----------
    weights : ndarray, shape (n,) or (n, n)
        ``W``: its diagonal, or the whole symmetric positive (semi)definite matrix.
    center : ndarray, shape (n,)
        Where the term is zero [rad/s, m/s].
    """

    weights: Any
    center: Any


@dataclass(slots=True)
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
        One name per row (``"wall"``, ``"qf3 - obstacle pillar"``); default
        ``"<limit name> <i>"``.
    """

    lower: Any = None
    upper: Any = None
    G: Any = None
    h: Any = None
    row_names: tuple[str, ...] = ()


@runtime_checkable
class Task(Protocol):
    """A task of the step: rows ``A x = b``, held exactly or, with a weight, in the cost.

    Attributes
    ----------
    name : str
        How messages name it.
    weight : float or None
        None (or ``inf``): the rows are equalities of the step. A number ``>= 0``: the
        term ``weight |A x - b|^2`` joins the cost [1 / (rad/s)^2, mixed units as the
        rows].
    """

    name: str
    weight: float | None

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
