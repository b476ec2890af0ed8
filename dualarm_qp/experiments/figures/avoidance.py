"""Several runs' clearance and grasp travel against time: ``dualarm-qp collisions``.

Two panels over a shared time axis: above, each run's nearest clearance (the smallest
distance of any checked pair at each sample) against the safety distance ``d_s`` and the
influence distance ``d_i``, with the contact level 0 and penetration (below 0) shaded;
below, each run's grasp coordinate against the grasp range. Read together, they show
when a sliding grasp moved to keep the clearance. Beside them, the same zoomed on the
time from when the first run comes within ``d_i``. (A single run's clearance, group by
group, is :mod:`.clearance`.)
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from .canvas import fixed_margins, limit_lines, new_figure, panel_title, tick_text
from .compare import Curve

#: The figure's height, the room for its title and the height of one line of a legend
#: or of the note at 7 points [in].
HEIGHT, TITLE_IN, LINE_IN = 7.4, 0.4, 0.16

#: Colour of the penetration band (below a clearance of 0).
PENETRATION_COLOUR = "C3"

#: The clearance axis stops this many influence distances above the safety distance
#: (pairs farther away give no row; their distance does not matter).
TOP_BANDS = 2.5


def _clearance_view(curves: Sequence[Curve], d_s: float, d_i: float,
                    window: tuple[float, float] | None = None) -> tuple[float, float, bool]:
    """Return the clearance axis (SI) over ``window`` and whether values lie above its top."""
    parts = []
    for c in curves:
        keep = np.isfinite(c.value)
        if window is not None:
            keep &= (c.t >= window[0]) & (c.t <= window[1])
        parts.append(c.value[keep])
    values = np.concatenate(parts) if any(p.size for p in parts) else np.zeros(1)
    lo = min(float(values.min()), 0.0)
    top = d_s + TOP_BANDS * (d_i - d_s)
    hi = min(max(float(values.max()), d_i), top)
    pad = 0.06 * (hi - lo)
    return lo - pad, hi + pad, bool(values.max() > hi + pad)


def near_window(curves: Sequence[Curve], d_i: float) -> tuple[float, float] | None:
    """Return the time window [s] in which the runs come near, or None when none does.

    It starts shortly before any run first comes within ``d_i`` and ends with the
    longest run.
    """
    first = [float(c.t[np.argmax(c.value < d_i)]) for c in curves
             if c.t.size and (c.value < d_i).any()]
    if not first:
        return None
    end = max(float(c.t[-1]) for c in curves if c.t.size)
    start = min(first)
    return max(start - 0.1 * (end - start), min(float(c.t[0]) for c in curves if c.t.size)), end


def _clearance_panel(ax: Any, curves: Sequence[Curve], d_s: float, d_i: float, scale: float,
                     unit: str, window: tuple[float, float] | None) -> bool:
    """Draw the clearances, the contact line, the penetration band, d_s and d_i."""
    for c in curves:
        ax.plot(c.t, c.value * scale, color=c.colour, lw=1.4, label=c.label)
    lo, hi, cut = _clearance_view(curves, d_s, d_i, window)
    band = ax.axhspan(lo * scale, 0.0, color=PENETRATION_COLOUR, alpha=0.12, lw=0,
                      label="penetration (below 0)")
    band.set_gid("penetration")
    ax.axhline(0.0, color="0.35", lw=0.8).set_gid("contact")
    limit_lines(ax, (d_s,), "safety_distance", scale=scale,
                label=f"safety distance d_s = {tick_text(d_s * scale)} {unit}")
    limit_lines(ax, (d_i,), "influence_distance", scale=scale, colour="C7", ls=":",
                label=f"influence distance d_i = {tick_text(d_i * scale)} {unit}")
    ax.set_ylim(lo * scale, hi * scale)
    if window is not None:
        ax.set_xlim(*window)
    return cut


def avoidance_figure(clearances: Sequence[Curve], grasps: Sequence[Curve], *,
                     safety_distance: float, influence_distance: float,
                     grasp_range: tuple[float, float], scale: float, unit: str,
                     title: str, note: str = "") -> Figure:
    """Draw runs' nearest clearance and grasp coordinate against time.

    Parameters
    ----------
    clearances : sequence of Curve
        Each run's nearest clearance [m] (SI), labelled for the legend.
    grasps : sequence of Curve
        Each run's grasp coordinate [m], in the same colours.
    safety_distance, influence_distance : float
        ``d_s`` and ``d_i`` [m].
    grasp_range : (float, float)
        The grasp range [m].
    scale : float
        SI to display units (``1e3`` for mm).
    unit : str
        The display unit of length (``"mm"``).
    title : str
        Figure title.
    note : str
        Small print under the axes.

    Returns
    -------
    Figure
        Axes ``[clearance, grasp]`` over the whole runs, then, when a run comes within
        ``d_i``, the same two zoomed on the time from then on (:func:`near_window`).
        The lines of ``d_s``, ``d_i`` and the grasp range carry the gids
        ``"limit:safety_distance"``, ``"limit:influence_distance"`` and
        ``"limit:grasp_range"``; the contact line ``"contact"``; the band below it
        ``"penetration"``.
    """
    window = near_window(clearances, influence_distance)
    fig = new_figure(figsize=(11, HEIGHT) if window is not None else (8, HEIGHT))
    grid = fig.add_gridspec(2, 2 if window is not None else 1, height_ratios=(1.5, 1),
                            width_ratios=(1.7, 1) if window is not None else None)
    columns = [None] if window is None else [None, window]
    cut = False
    axes = []
    for col, win in enumerate(columns):
        ax1 = fig.add_subplot(grid[0, col])
        ax2 = fig.add_subplot(grid[1, col], sharex=ax1)
        cut |= _clearance_panel(ax1, clearances, safety_distance, influence_distance,
                                scale, unit, win)
        for c in grasps:
            ax2.plot(c.t, c.value * scale, color=c.colour, lw=1.4)
        limit_lines(ax2, grasp_range, "grasp_range", scale=scale,
                    label=f"grasp range {tick_text(grasp_range[0] * scale)} to "
                          f"{tick_text(grasp_range[1] * scale)} {unit}")
        ax2.set_xlabel("t [s]")
        if win is not None:
            panel_title(ax1, f"from t = {win[0]:.3g} s, as the runs come within d_i",
                        fontsize=9)
        axes += [ax1, ax2]
    axes[0].set_ylabel(f"nearest clearance [{unit}]", fontsize=9)
    axes[1].set_ylabel(f"grasp [{unit}]", fontsize=9)
    handles, labels = axes[0].get_legend_handles_labels()
    more, more_labels = axes[1].get_legend_handles_labels()
    fig.legend([*handles, *more], [*labels, *more_labels], loc="upper center",
               bbox_to_anchor=(0.5, 1.0 - TITLE_IN / HEIGHT), ncol=2, fontsize=7,
               frameon=False)
    rows = -(-(len(labels) + len(more_labels)) // 2)
    if cut:
        top = safety_distance + TOP_BANDS * (influence_distance - safety_distance)
        note = (note + "\n" if note else "") + (
            f"The clearance axes stop at {tick_text(top * scale)} {unit}: farther pairs give "
            "no row.")
    fig.suptitle(title, fontsize=10)
    fixed_margins(fig, left=0.85, right=0.2, top=TITLE_IN + LINE_IN * rows + 0.35,
                  bottom=0.6 + (LINE_IN * (note.count("\n") + 1) if note else 0.0),
                  hspace=0.12, wspace=0.15)
    if note:
        fig.text(0.01, 0.012, note, fontsize=7, color="0.3")
    return fig


__all__ = ["avoidance_figure", "near_window"]
