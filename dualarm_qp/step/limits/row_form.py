"""The compiled form of a limit's rows: rows the kernel computes with the step's parts.

A limit whose rows come from a kernel object that reads the step's kinematics (the
collision scene's velocity damper, ``kernel.DamperScene``) declares it as its
``compiled_rows``, a :class:`RowForm`. The step builder hands the object to the kernel's
parts (``kernel.StepParts.add_rows``), which compute the rows in the call that computes
the kinematics and the boxes; with an exact solver the same call solves the step with
them (:mod:`dualarm_qp.step.build`). The limit's ``constraint`` is
:func:`compiled_rows_constraint`: the same kernel object's rows at the context's
kinematics, which is what a limit asked on its own gives. A subclass that overrides
``constraint`` has no compiled form: its own method runs at each step.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..._compiled import kernel
from ...errors import NonFiniteError
from ..context import StepContext
from ..parts import Constraint

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class RowForm:
    """Rows a kernel damper computes at the step's kinematics.

    Attributes
    ----------
    damper : kernel.DamperScene
        Computes ``(finite, pairs, G, h)`` from both arms' chains and the carried
        object's Jacobian and pose.
    names : tuple of str
        The name of the row of each of the damper's pairs.
    nonfinite : str
        What a :class:`~dualarm_qp.errors.NonFiniteError` names when the damper finds a
        frame or a Jacobian off the finite numbers.
    """

    damper: Any
    names: tuple[str, ...]
    nonfinite: str

    def constraint(self, finite: bool, pairs: NDArray[np.int64], G: FloatArray,
                   h: FloatArray) -> Constraint:
        """Return the rows of the damper's answer ``(finite, pairs, G, h)`` as a constraint.

        Raises
        ------
        NonFiniteError
            The damper found a frame or a Jacobian that is not finite.
        """
        if not finite:
            raise NonFiniteError(self.nonfinite)
        if not len(h):
            return Constraint()
        names = self.names
        return Constraint(G=G, h=h, row_names=tuple([names[k] for k in pairs.tolist()]))


def compiled_rows_constraint(self: Any, ctx: StepContext) -> Constraint:
    """Return the rows of the limit's compiled form at the step's context.

    The ``constraint`` of a limit whose rows are its compiled form (``self.compiled_rows``,
    a :class:`RowForm`): one call of its damper on the context's chains, the carried
    object's Jacobian and pose (what the builder's kernel call computes with the step's
    parts).

    Raises
    ------
    NonFiniteError
        A frame or a Jacobian the rows read is not finite.
    """
    form: RowForm = self.compiled_rows
    return form.constraint(*form.damper.rows(ctx.leader_arm.chain, ctx.follower_arm.chain,
                                             ctx.carry.J_object, ctx.carry.T_object))


def compiled_rows(limit: Any) -> RowForm | None:
    """Return the compiled form of a limit's rows, or None (its constraint runs in Python).

    A limit's rows are compiled when it declares a :class:`RowForm` holding a kernel
    damper (``limit.compiled_rows``) and its ``constraint`` is
    :func:`compiled_rows_constraint`: a subclass that overrides ``constraint`` runs its
    own.
    """
    if getattr(type(limit), "constraint", None) is not compiled_rows_constraint:
        return None
    form = getattr(limit, "compiled_rows", None)
    return form if isinstance(form, RowForm) and isinstance(
        form.damper, kernel.DamperScene) else None


def constraints_in_order(compiled: Sequence[tuple[int, RowForm]],
                         answers: Sequence[tuple[bool, NDArray[np.int64], FloatArray,
                                                 FloatArray]],
                         python: Sequence[tuple[int, Any]], ctx: StepContext | None
                         ) -> Iterator[tuple[int, Constraint]]:
    """Yield the constraint of every limit but the compiled boxes, in the limits' order.

    Parameters
    ----------
    compiled, answers : sequence
        The compiled row limits (index, form) and the kernel's answer of each (what
        ``kernel.StepParts.prepare`` computed with the step's parts).
    python : sequence of (int, Limit)
        The limits whose ``constraint(ctx)`` runs in Python, and their indices.
    ctx : StepContext or None
        The step's context (None when ``python`` is empty).

    The kernel computed every compiled limit's rows in its call already; their
    constraints, and the Python limits' ``constraint(ctx)`` calls, are made when their
    turn comes, as in a loop over the limits: a limit's error (a
    :class:`~dualarm_qp.errors.NonFiniteError` of compiled rows, whatever a Python limit
    raises) comes after every constraint before it was taken, and no later limit is
    asked.
    """
    at = 0
    for k, limit in python:
        while at < len(compiled) and compiled[at][0] < k:
            yield compiled[at][0], compiled[at][1].constraint(*answers[at])
            at += 1
        yield k, limit.constraint(ctx)
    while at < len(compiled):
        yield compiled[at][0], compiled[at][1].constraint(*answers[at])
        at += 1


__all__ = ["RowForm", "compiled_rows", "compiled_rows_constraint", "constraints_in_order"]
