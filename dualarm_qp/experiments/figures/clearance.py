"""The clearance figure of a run with a collision scene (``clearance.png``).

The smallest distance of each group of pairs against time (the ``clearance_*`` columns
of ``trajectory.csv``: arm against arm, arms against the object, against the obstacles,
an arm against itself), read against the safety distance ``d_s`` (no pair may come
closer), ``d_s`` less the allowance for one step's second-order error (a run with
collision avoidance fails below it) and the influence distance ``d_i`` (pairs closer
than it get a row in the step). The smallest distance is marked with its pair.

Lengths are shown in the experiment file's unit (mm or m). Far pairs do not matter to
the limit: the axis stops a few ``d_i`` up, and larger distances are drawn on its top
edge (the legend says so).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from matplotlib.figure import Figure

from ...collision.settings import CLEARANCE_ALLOWANCE
from .canvas import (
    LIMIT_COLOUR,
    TICKS,
    few_ticks,
    fixed_margins,
    limit_lines,
    new_figure,
    outside_mask,
    outside_spans,
    panel_title,
    shade_spans,
)
from .ready import builder, take, ticks_ahead
from .rundata import PlotLimits, RunData

#: The file name of the figure.
CLEARANCE_FIGURE = "clearance.png"

#: The clearance columns of ``trajectory.csv``, with their names and colours.
CLEARANCE_COLUMNS = (("clearance_arm_arm", "arm - arm", "C0"),
                     ("clearance_arm_object", "arm - object", "C2"),
                     ("clearance_obstacles", "arms and object - obstacles", "C1"),
                     ("clearance_self", "arm - itself", "C4"))

#: The figure's height and its margin above the axis [in].
HEIGHT, TOP = 5.0, 0.35

#: The axis stops this many influence distances up.
TOP_PER_INFLUENCE = 3.0


@builder("clearance")
def _axes() -> tuple[Figure, Any]:
    """Return the figure and its axis (built ahead by a drawing process: :mod:`.ready`)."""
    fig = new_figure(figsize=(8, HEIGHT))
    ax = fig.subplots()
    few_ticks(ax)
    ticks_ahead(ax, count=TICKS + 1)
    return fig, ax


def has_clearance(data: RunData) -> bool:
    """Whether the run recorded a clearance (its task had a collision scene)."""
    return any(data.has(name) for name, _, _ in CLEARANCE_COLUMNS)


def clearance_figure(data: RunData, limits: PlotLimits, title: str = "") -> Figure:
    """Smallest distance of each group of pairs against time, with ``d_s`` and ``d_i``.

    Parameters
    ----------
    data : RunData
        The run's trace, with its ``clearance_*`` columns [m].
    limits : PlotLimits
        Its ``clearance`` (``d_s``, ``d_i``) [m] and whether the step kept it.
    title : str
        Title prefix.

    Lines carry gids: ``limit:safety_distance``, ``limit:influence_distance``,
    ``limit:clearance_allowance`` (only when collision avoidance was on), and
    ``clearance:<column>`` for each group drawn; samples below ``d_s - allowance`` are
    shaded (``outside:clearance``).
    """
    fig, ax = take("clearance")
    t = data.t
    per_m, unit = limits.units.per_m, limits.units.length
    d_s, d_i = limits.clearance if limits.clearance is not None else (np.nan, np.nan)
    drawn = [(name, label, colour, data.col(name)) for name, label, colour in CLEARANCE_COLUMNS
             if data.has(name) and np.isfinite(data.col(name)).any()]
    nearest = (np.min(np.column_stack([v for *_, v in drawn]), axis=1) if drawn
               else np.full(len(t), np.inf))
    finite = nearest[np.isfinite(nearest)]
    reference = d_i if np.isfinite(d_i) else (float(finite.max()) if finite.size else 0.1)
    top = TOP_PER_INFLUENCE * reference
    low = min(0.0, float(finite.min()) if finite.size else 0.0)
    ax.set_ylim((low - 0.05 * top) * per_m, 1.05 * top * per_m)
    for name, label, colour, values in drawn:
        line, = ax.plot(t, np.minimum(values, top) * per_m, color=colour, lw=1.2, label=label)
        line.set_gid(f"clearance:{name}")
    if np.isfinite(d_i):
        limit_lines(ax, (d_i,), "influence_distance", scale=per_m, colour="0.45", ls=":",
                    label=f"d_i = {d_i * per_m:.4g} {unit}: pairs closer get a row")
    limit_lines(ax, (d_s,), "safety_distance", scale=per_m,
                label=f"d_s = {d_s * per_m:.4g} {unit}: the safety distance")
    if limits.clearance_enforced and np.isfinite(d_s):
        floor = d_s - CLEARANCE_ALLOWANCE
        limit_lines(ax, (floor,), "clearance_allowance", scale=per_m, ls=":",
                    label=f"d_s - {CLEARANCE_ALLOWANCE * per_m:.3g} {unit}: the run fails below")
        shade_spans(ax, outside_spans(t, outside_mask(nearest, floor)), "clearance",
                    label="below it")
    if np.isfinite(nearest).any():
        k = int(np.nanargmin(np.where(np.isfinite(nearest), nearest, np.nan)))
        pair = str(data.columns["clearance_pair"][k]) if data.has("clearance_pair") else ""
        ax.plot([t[k]], [nearest[k] * per_m], "o", color=LIMIT_COLOUR, ms=5, gid="clearance:min",
                label=f"smallest {nearest[k] * per_m:.4g} {unit} at t = {t[k]:.3g} s"
                      + (f": {pair}" if pair else ""))
    if any((values > top).any() for *_, values in drawn):
        ax.plot([], [], color="none",
                label=f"above {top * per_m:.4g} {unit}: on the top edge")
    ax.set_xlabel("t [s]")
    ax.set_ylabel(f"smallest distance [{unit}]")
    # The legend under the axis, below the time axis's label: two columns, each row
    # about 0.16 in high at this font size.
    rows = -(-len(ax.get_legend_handles_labels()[1]) // 2)
    bottom = 0.62 + 0.16 * rows
    axis_height = HEIGHT - TOP - bottom
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.5 / axis_height),
              ncol=2, frameon=False)
    state = ("" if limits.clearance_enforced
             else " (collision avoidance off: measured only)")
    panel_title(ax, (title + ": " if title else "") + "clearance of each group of pairs" + state,
                fontsize=10)
    fixed_margins(fig, top=TOP, bottom=bottom)
    return fig


__all__ = ["CLEARANCE_COLUMNS", "CLEARANCE_FIGURE", "clearance_figure", "has_clearance"]
