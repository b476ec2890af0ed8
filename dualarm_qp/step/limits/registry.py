"""Which limits a step stacks: one factory per limit, registered by name.

A limit module defines its class and registers a factory with :func:`register_limit`.
The factory reads the step's settings (:class:`LimitSetup`) and returns the limit, or
None when those settings do not ask for it. :func:`standard_limits` builds every
registered limit the settings ask for, in registration order: that list is the step's
limits (a user's own limits are added to it, see
:class:`~dualarm_qp.step.build.StepBuilder`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from ...task.scene import DualArmTask
from ..layout import Layout
from ..options import StepOptions


@dataclass(frozen=True)
class LimitSetup:
    """What a limit factory reads.

    Attributes
    ----------
    task : DualArmTask
        Arms (their ranges, speed and acceleration limits), object and path.
    options : StepOptions
        The step's settings (which limits are on, the grasp's limits).
    layout : Layout
        The slices of the decision vector.
    leader_bounds : bool
        Impose the leader's own limits (hard-limit solvers); False leaves the leader's
        joints free (the paper's methods, which ignore limits by design).
    """

    task: DualArmTask
    options: StepOptions
    layout: Layout
    leader_bounds: bool


#: A factory: the limit the settings ask for (a :class:`~..parts.Limit`, or a kernel
#: part), or None.
LimitFactory = Callable[[LimitSetup], Any]

_FACTORIES: dict[str, LimitFactory] = {}


def register_limit(name: str, factory: LimitFactory) -> None:
    """Register the factory of the limit called ``name`` (one line per limit module)."""
    _FACTORIES[name] = factory


def registered_limits() -> tuple[str, ...]:
    """Names of the registered limits, in stacking order."""
    return tuple(_FACTORIES)


def standard_limits(setup: LimitSetup) -> list[Any]:
    """Every registered limit that ``setup`` asks for, in registration order."""
    limits = []
    for factory in _FACTORIES.values():
        limit = factory(setup)
        if limit is not None:
            limits.append(limit)
    return limits


__all__ = ["LimitFactory", "LimitSetup", "register_limit", "registered_limits",
           "standard_limits"]
