"""The compiled form of a limit's box: what the kernel computes for it every step.

A standard box limit (joint and grasp range, joint and grasp speed, acceleration)
declares its box as a :class:`BoxForm`, next to its registered factory: a kind and the
per-variable numbers fixed when the limit is built. The step builder hands the forms to
the kernel once (``kernel.StepParts``), which computes their boxes with the step's
kinematics, equality and centring in one call (``src/kernel/step_parts.cpp``). The
limit's own ``constraint(ctx)`` gives the same box from the same compiled function
(:meth:`BoxForm.box`), so a limit read on its own and the step agree to the bit.

A limit's box is compiled when the limit declares its form (``compiled``) and its
``constraint`` is :func:`compiled_constraint`; a subclass that overrides ``constraint``
runs its own. A limit without a compiled form (the collision and torque limits, a
user's own) runs its Python ``constraint(ctx)`` on the step's context; its boxes and
rows join the kernel's (``docs/benchmarks.md`` states what that path costs). The form
is read when the builder is made: a limit changed afterwards needs a new builder.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..._compiled import kernel
from ..context import StepContext
from ..parts import Constraint

FloatArray = NDArray[np.float64]

#: The kinds of compiled box (``src/kernel/step_parts.hpp``).
RANGE: int = kernel.BOX_RANGE
SPEED: int = kernel.BOX_SPEED
ACCELERATION: int = kernel.BOX_ACCELERATION

_NO_MASK = np.zeros(0, dtype=bool)


@dataclass(frozen=True, eq=False)
class BoxForm:
    """A limit's box as the kernel computes it.

    Attributes
    ----------
    kind : int
        :data:`RANGE`: ``range_box`` of the rates to the range ends, with recovery rates
        ``p`` [rad/s, m/s] and ``off`` the variables it does not bound; :data:`SPEED`:
        ``[-p, p]`` with ``p`` the speed limits [rad/s, m/s]; :data:`ACCELERATION`:
        ``[x_applied - p, x_applied + p]`` with ``p = a dt`` [rad/s, m/s], cut by the
        braking bound of each range end (:func:`.acceleration.braking_bound`).
    p : ndarray, shape (n,)
        The per-variable numbers (``inf``: none).
    off : ndarray of bool, shape (n,)
        :data:`RANGE` only: the variables the limit does not bound (empty otherwise).
    """

    kind: int
    p: FloatArray
    off: NDArray[np.bool_] = field(default_factory=lambda: _NO_MASK)

    def __post_init__(self) -> None:
        # Copies, read-only: the form is what the builder hands the kernel once.
        p = np.array(self.p, dtype=np.float64, order="C", ndmin=1)
        p.flags.writeable = False
        object.__setattr__(self, "p", p)
        off = np.array(self.off, dtype=bool, order="C", ndmin=1) if self.kind == RANGE \
            else _NO_MASK
        off.flags.writeable = False
        object.__setattr__(self, "off", off)

    def box(self, ctx: StepContext) -> Constraint:
        """Return the box at the step's context (the kernel's functions, as in the step).

        A range box reads the context's ``rate_lo`` and ``rate_hi`` only, a speed box
        nothing; an acceleration box also ``x_applied`` and ``dt``.
        """
        if self.kind == RANGE:
            lower, upper = kernel.range_box(ctx.rate_lo, ctx.rate_hi, self.p, self.off)
        elif self.kind == SPEED:
            lower, upper = -self.p, self.p
        else:
            lower, upper = kernel.limit_box(self.kind, self.p, self.off, ctx.rate_lo,
                                            ctx.rate_hi, ctx.x_applied, ctx.dt)
        return Constraint(lower=lower, upper=upper)


def compiled_constraint(self: Any, ctx: StepContext) -> Constraint:
    """Return the box of the limit's compiled form at the step's context.

    The ``constraint`` of a limit whose box is its compiled form (``self.compiled``, a
    :class:`BoxForm`): the builder then computes that box in the kernel with the step's
    standard parts, and a limit read on its own gives the same box.
    """
    form: BoxForm = self.compiled
    return form.box(ctx)


def compiled_form(limit: Any) -> BoxForm | None:
    """Return the compiled form of a limit's box, or None (its constraint runs in Python).

    A limit's box is compiled when it declares a :class:`BoxForm` (``limit.compiled``)
    and its ``constraint`` is :func:`compiled_constraint` (the box of that form): a
    subclass that overrides ``constraint`` runs its own.
    """
    form = getattr(limit, "compiled", None)
    if isinstance(form, BoxForm) and getattr(type(limit), "constraint", None) is \
            compiled_constraint:
        return form
    return None


__all__ = ["ACCELERATION", "RANGE", "SPEED", "BoxForm", "compiled_constraint",
           "compiled_form"]
