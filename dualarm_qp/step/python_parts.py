"""Parts written in Python, as the step's loop asks them (private).

The kernel's loop (:class:`~dualarm_qp.step.build.StepBuilder`) asks kernel parts
(``kernel.Task``, ``kernel.CostTerm``, ``kernel.Limit``). A Python subclass of one of
them overrides its method; the kernel calls it through a trampoline with the step's
:class:`~.context.StepContext`. A part of the user's that is no such subclass (any
object of the protocols of :mod:`.parts`) is wrapped here in one that asks it. What a
Python method gives (an :class:`~.parts.Equality`, :class:`~.parts.Quadratic` or
:class:`~.parts.Constraint`) is checked and taken in the kernel's form by the functions
below, naming the part; the loop then stacks it with the others, in its place.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from .._compiled import kernel
from ..errors import InvalidInputError, NonFiniteError, ShapeError
from .parts import Constraint, CostTerm, Equality, Limit, Quadratic, Task

if TYPE_CHECKING:
    from .context import StepContext

FloatArray = NDArray[np.float64]


def _numbers(value: Any, what: str) -> FloatArray:
    """``value`` as a C-ordered float64 array, or an error naming ``what``."""
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError, OverflowError) as err:
        raise InvalidInputError(f"{what} are not numbers: {err}") from err
    return arr if arr.flags.c_contiguous else np.ascontiguousarray(arr)


def _rows(G: Any, h: Any, names: tuple[str, ...], n: int, what: str
          ) -> tuple[FloatArray, FloatArray, list[str]]:
    """Rows ``G x <= h`` checked: ``G`` (p, n) finite, ``h`` (p,) without NaN, p names."""
    G_k = np.atleast_2d(_numbers(G, f"the rows of {what}"))
    h_k = np.atleast_1d(_numbers(h, f"the rows of {what}"))
    if h_k.ndim != 1 or G_k.shape != (h_k.shape[0], n):
        raise ShapeError(f"the rows of {what}", (h_k.shape[0] if h_k.ndim == 1 else -1, n),
                         G_k.shape)
    if names and len(names) != h_k.shape[0]:
        raise ShapeError(f"the row names of {what}", (h_k.shape[0],), (len(names),))
    if kernel.first_defect([G_k], [h_k]) >= 0:
        raise NonFiniteError(f"the rows of {what}")
    return G_k, h_k, list(names)


def kernel_constraint(c: Constraint, name: str, n: int) -> Any:
    """Return a limit's :class:`~.parts.Constraint` checked, in the kernel's form.

    Raises
    ------
    ShapeError, InvalidInputError
        Bounds that are not one number per variable, rows that are not ``(p, n)`` with
        ``p`` right-hand sides (and ``p`` names, if any).
    NonFiniteError
        Rows with NaN or infinity, right-hand sides with NaN (NaN bounds are named when
        the step intersects the boxes).
    """
    what = f"the limit '{name}'"
    bounds: list[FloatArray | None] = []
    for side, value in (("lower", c.lower), ("upper", c.upper)):
        if value is None:
            bounds.append(None)
            continue
        arr = _numbers(value, f"the {side} bounds of {what}")
        if arr.shape != (n,):
            raise ShapeError(f"the {side} bounds of {what}", (n,), arr.shape)
        bounds.append(arr)
    G = h = None
    names: list[str] = []
    if c.G is not None and c.h is not None and np.size(c.h):
        G, h, names = _rows(c.G, c.h, tuple(c.row_names), n, what)
        if not names:
            names = [f"{name} {i + 1}" for i in range(h.shape[0])]
    return kernel.Constraint(lower=bounds[0], upper=bounds[1], G=G, h=h, row_names=names)


def kernel_equality(eq: Equality, name: str, n: int) -> Any:
    """Return a task's :class:`~.parts.Equality` checked, in the kernel's form.

    Raises
    ------
    ShapeError, InvalidInputError
        Rows that are not ``(m, n)`` numbers with ``m`` right-hand sides (and ``m``
        names, if any). Non-finite rows are named when the step stacks them.
    """
    what = f"the rows of the task '{name}'"
    A = np.atleast_2d(_numbers(eq.A, what))
    b = np.atleast_1d(_numbers(eq.b, what))
    if b.ndim != 1 or A.shape != (b.shape[0], n):
        raise ShapeError(what, (b.shape[0] if b.ndim == 1 else -1, n), A.shape)
    names = list(eq.names) or [f"{name} {i + 1}" for i in range(b.shape[0])]
    if len(names) != b.shape[0]:
        raise ShapeError(f"the row names of the task '{name}'", (b.shape[0],), (len(names),))
    return kernel.Equality(A, b, names)


def kernel_quadratic(q: Quadratic, name: str, n: int) -> Any:
    """Return a cost term's :class:`~.parts.Quadratic` checked, in the kernel's form.

    Raises
    ------
    ShapeError, InvalidInputError
        Weights that are not ``(n,)`` or ``(n, n)`` numbers, a centre that is not ``n``
        numbers, negative diagonal weights. Non-finite values are named when the step
        sums the cost.
    """
    what = f"the cost term '{name}'"
    W = _numbers(q.weights, f"the weights of {what}")
    c = _numbers(q.center, f"the centre of {what}")
    if c.shape != (n,):
        raise ShapeError(f"the centre of {what}", (n,), c.shape)
    if W.shape not in ((n,), (n, n)):
        raise ShapeError(f"the weights of {what}", (n,), W.shape)
    if W.ndim == 1:
        if not bool((W >= 0).all()):
            raise InvalidInputError(f"the weights of {what} must be >= 0")
        return kernel.Quadratic(w=W, center=c)
    return kernel.Quadratic(W=W, center=c)


class PythonLimit(kernel.Limit):
    """A limit of the user's as a kernel part: the kernel's loop asks its ``constraint``.

    What it gives is checked and taken in the kernel's form
    (:func:`kernel_constraint`, naming the limit).

    Parameters
    ----------
    limit : Limit
        The user's limit (``name``, ``gives_rows``, ``constraint(ctx)``).
    """

    def __init__(self, limit: Limit) -> None:
        super().__init__()
        self.limit = limit
        self.name = limit.name
        self.gives_rows = limit.gives_rows

    def constraint(self, ctx: StepContext) -> Constraint:
        """Return the user's limit's constraint at ``ctx``."""
        return self.limit.constraint(ctx)

    def __reduce__(self) -> tuple[Any, ...]:
        return (PythonLimit, (self.limit,))


class PythonTask(kernel.Task):
    """A task of the user's as a kernel part: the kernel's loop asks its ``equality``.

    Parameters
    ----------
    task : Task
        The user's task (``name``, ``weight``, ``equality(ctx)``).

    Raises
    ------
    InvalidInputError
        A weight that is neither None nor a number ``>= 0``.
    """

    def __init__(self, task: Task) -> None:
        super().__init__()
        self.task = task
        self.name = task.name
        weight = getattr(task, "weight", None)
        if weight is not None:
            if not (isinstance(weight, (int, float)) and weight >= 0):
                raise InvalidInputError(f"the task '{task.name}' has weight {weight!r}: a "
                                        "number >= 0, or None for equality rows")
            self.weight = float(weight)

    def equality(self, ctx: StepContext) -> Equality:
        """Return the user's task's rows at ``ctx``."""
        return self.task.equality(ctx)

    def __reduce__(self) -> tuple[Any, ...]:
        return (PythonTask, (self.task,))


class PythonCost(kernel.CostTerm):
    """A cost term of the user's as a kernel part: the kernel's loop asks its ``quadratic``.

    Parameters
    ----------
    cost : CostTerm
        The user's term (``name``, ``quadratic(ctx)``).
    """

    def __init__(self, cost: CostTerm) -> None:
        super().__init__()
        self.cost = cost
        self.name = cost.name

    def quadratic(self, ctx: StepContext) -> Quadratic:
        """Return the user's term at ``ctx``."""
        return self.cost.quadratic(ctx)

    def __reduce__(self) -> tuple[Any, ...]:
        return (PythonCost, (self.cost,))


def task_part(task: Any) -> Any:
    """Return ``task`` as the kernel's loop asks it (a kernel task as it is)."""
    if isinstance(task, kernel.Task):
        return task
    if not (isinstance(getattr(task, "name", None), str)
            and callable(getattr(task, "equality", None))):
        raise InvalidInputError(
            f"{task!r} is not a task: a task has a str 'name', a 'weight' (None or a "
            "number) and a method 'equality(ctx)' (dualarm_qp.step.parts)")
    return PythonTask(task)


def cost_part(cost: Any) -> Any:
    """Return ``cost`` as the kernel's loop asks it (a kernel cost term as it is)."""
    if isinstance(cost, kernel.CostTerm):
        return cost
    if not (isinstance(getattr(cost, "name", None), str)
            and callable(getattr(cost, "quadratic", None))):
        raise InvalidInputError(
            f"{cost!r} is not a cost term: a cost term has a str 'name' and a method "
            "'quadratic(ctx)' (dualarm_qp.step.parts)")
    return PythonCost(cost)


def limit_part(limit: Any) -> Any:
    """Return ``limit`` as the kernel's loop asks it (a kernel limit as it is)."""
    if isinstance(limit, kernel.Limit):
        return limit
    if not (isinstance(getattr(limit, "name", None), str)
            and callable(getattr(limit, "constraint", None))
            and isinstance(getattr(limit, "gives_rows", None), bool)):
        raise InvalidInputError(
            f"{limit!r} is not a limit: a limit has a str 'name', a bool 'gives_rows' and "
            "a method 'constraint(ctx)' (dualarm_qp.step.parts)")
    return PythonLimit(limit)


__all__ = ["PythonCost", "PythonLimit", "PythonTask", "cost_part", "kernel_constraint",
           "kernel_equality", "kernel_quadratic", "limit_part", "task_part"]
