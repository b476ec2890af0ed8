"""A run's figures' empty axes, built before the run's trace comes (the drawing process).

A figure's axes and their ticks are matplotlib objects of many artists each: building
them ahead takes 7 to 21 % of the CPU time of drawing a run's figures off the command's
path (docs/benchmarks.md), for the figures whose axes do not depend on the trace
(``grasp.png``, ``tracking.png``, ``closure.png``, ``clearance.png``, and the lane axis
of ``joints.png`` and ``rates.png``, sized once the trace gives the joints). The
drawing process (:mod:`.process`) builds them with :func:`prepare` while it waits for its
job, that is while the command runs the experiment; each figure then takes its own
(:func:`take`) instead of building it. A figure drawn anywhere else builds its axes when
it is drawn: the same axes, the same picture.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from matplotlib.figure import Figure

#: The axes built ahead, by the name of their builder (:func:`prepare`).
_READY: dict[str, tuple[Figure, Any]] = {}

#: The builders :func:`prepare` calls, by name: each returns a figure and its axes.
BUILDERS: dict[str, Callable[[], tuple[Figure, Any]]] = {}


def builder(name: str) -> Callable[[Callable[[], tuple[Figure, Any]]],
                                   Callable[[], tuple[Figure, Any]]]:
    """Register a function that builds a figure's axes under ``name`` (a decorator)."""
    def register(build: Callable[[], tuple[Figure, Any]]) -> Callable[[], tuple[Figure, Any]]:
        BUILDERS[name] = build
        return build
    return register


def take(name: str) -> tuple[Figure, Any]:
    """Return the figure and axes built ahead under ``name``, else build them now.

    Each one built ahead is taken once.
    """
    ready = _READY.pop(name, None)
    return ready if ready is not None else BUILDERS[name]()


def prepare(stop: Callable[[], bool] = lambda: False) -> None:
    """Build the axes of every registered builder, for :func:`take` to return.

    ``stop`` is asked before each: once it says True (the job has come), the rest are
    built when they are drawn.
    """
    for name, build in BUILDERS.items():
        if stop():
            return
        if name not in _READY:
            _READY[name] = build()


def ticks_ahead(*axes: Any, count: int, which: str = "xy") -> None:
    """Create ``count`` major ticks on each visible axis ``which`` (x, y) of ``axes``.

    An axis makes its ticks when it is first drawn, as many as its locator gives; made
    ahead, they are used then (the ones not needed are not drawn).
    """
    for ax in axes:
        for axis in [ax.xaxis] * ("x" in which) + [ax.yaxis] * ("y" in which):
            if axis.get_visible():
                axis.get_major_ticks(count)


__all__ = ["BUILDERS", "builder", "prepare", "take", "ticks_ahead"]
