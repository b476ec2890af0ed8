"""The joints and joint rates of a run drawn as lanes: one axis, one lane per joint.

``joints.png`` and ``rates.png`` draw both arms in one axis in which every joint has a
horizontal lane of its own: the leader's joints from the top, then, below a heavier
line, the follower's. A lane draws its joint's values scaled to the joint's limits, so
that the limits are the same two dashed lines in every lane, whatever the joint's range
or speed:

- ``joints.png``: the lower end of the range on the lower line, the upper end on the
  upper one;
- ``rates.png``: the commanded and the realised rate, minus and plus the speed limit on
  the lines (zero, the lane's middle, is dotted); with acceleration limits kept, a second
  axis beside it draws the realised accelerations against ``qdd_max`` the same way.

The label beside each lane gives the joint (``q3``) and its limits in the experiment
file's units (named in the title), so that the lines read as values. A value beyond a
limit is drawn in the lane's margin (grey), at the same scale, up to the lane's edge,
where it is clipped (the label then gives the farthest value reached); the time it spends
beyond is shaded across the lane. A side without a limit (a continuous joint, no speed
limit) is scaled to the values reached instead, and has no line.

One axis for all the joints rather than one per joint: the same information at a
fraction of the drawing's cost (each axis costs matplotlib its own ticks, spines and
labels, and those were most of the figures' time).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from matplotlib.collections import LineCollection, PolyCollection
from matplotlib.figure import Figure

from .canvas import (
    LIMIT_COLOUR,
    TICKS,
    few_ticks,
    fixed_margins,
    new_figure,
    outside_mask,
    outside_spans,
    panel_title,
)
from .lane_model import CLIP, LIMIT, Lane, range_lane, speed_lane
from .ready import builder, take, ticks_ahead
from .rundata import PlotLimits, RunData

#: The arms, as their columns' letter, their name and their traces' colour.
ARMS = (("l", "leader", "C2"), ("f", "follower", "C0"))

#: The background of a lane beyond its limits (within them: white).
OUTSIDE_COLOUR = "0.93"

#: Height of one lane [in].
LANE_HEIGHT = 0.3

#: Widths [in]: the arms' names and the lanes' labels left of an axis, the right margin.
LABEL_WIDTH, RIGHT = 1.3, 0.2

#: Width [in] of the axis of a figure of one axis, and of each of a figure of two or three.
AXIS_WIDTH = {1: 7.6, 2: 5.0, 3: 4.2}


def _lane_figure(columns: int) -> tuple[Figure, Any]:
    """Return a figure of ``columns`` lane axes side by side, not yet sized."""
    width = AXIS_WIDTH[columns]
    fig = new_figure(figsize=(columns * (LABEL_WIDTH + width) + RIGHT, 4.0))
    axes = fig.subplots(1, columns, squeeze=False)[0]
    for ax in axes:
        ax.set_facecolor(OUTSIDE_COLOUR)
        few_ticks(ax)
        ax.tick_params(labelsize=7)
        ax.set_yticks([])
        ax.set_xlabel("t [s]", fontsize=8)
    ticks_ahead(*axes, count=TICKS + 1, which="x")
    return fig, axes


#: The figures of one lane axis built ahead (:mod:`.ready`): one for the joints, one
#: for the rates (without acceleration or jerk limits).
builder("lanes:joints")(lambda: _lane_figure(1))
builder("lanes:rates")(lambda: _lane_figure(1))


def lane_axes(columns: int, lanes: int, top: float, bottom: float,
              ahead: str | None = None) -> tuple[Figure, Any]:
    """Return a figure with ``columns`` lane axes side by side, each ``lanes`` lanes high.

    Parameters
    ----------
    columns : int
        Axes (1; or 2: rates and accelerations).
    lanes : int
        Lanes per axis (both arms' joints).
    top, bottom : float
        Margins [in] above and below the axes.
    ahead : str, optional
        The figure of one axis built ahead (:func:`~.ready.take`) to use, if any.
    """
    width = AXIS_WIDTH[columns]
    fig, axes = take(ahead) if ahead is not None and columns == 1 else _lane_figure(columns)
    fig.set_size_inches(columns * (LABEL_WIDTH + width) + RIGHT,
                        lanes * LANE_HEIGHT + top + bottom)
    fixed_margins(fig, left=LABEL_WIDTH, right=RIGHT, top=top, bottom=bottom,
                  wspace=LABEL_WIDTH / width)
    for ax in axes:
        ax.set_ylim(-0.5, lanes - 0.5)
    return fig, axes


def middle(k: int, lanes: int) -> float:
    """Return the middle of lane ``k`` (0-based, from the top) of ``lanes``."""
    return float(lanes - 1 - k)


def label_lanes(ax: Any, drawn: Sequence[Lane], counts: Sequence[int], *,
                zero: bool = False) -> None:
    """Finish a lane axis: each lane's label beside it, the lines between the lanes.

    Also the white band between each lane's limits (beyond them, the axis's grey), each
    arm's name beside its lanes (``counts``: the leader's and the follower's) and, with
    ``zero``, each lane's zero as a dotted line. Each of these is one artist for the
    whole axis, the labels one text each: no tick (a tick is several artists).
    """
    lanes = len(drawn)
    mids = [middle(k, lanes) for k in range(lanes)]
    across = ax.get_yaxis_transform()  # x: the axis's width, 0 to 1; y: data
    ax.add_collection(PolyCollection([[(0.0, m - LIMIT), (1.0, m - LIMIT), (1.0, m + LIMIT),
                                       (0.0, m + LIMIT)] for m in mids],
                                     facecolors="white", lw=0, zorder=0, transform=across),
                      autolim=False)
    between = [k + 0.5 for k in range(lanes - 1)]
    arms_meet = lanes - 0.5 - counts[0]
    ax.add_collection(LineCollection([[(0.0, y), (1.0, y)] for y in between],
                                     colors=["0.15" if y == arms_meet else "0.6"
                                             for y in between],
                                     lw=[1.2 if y == arms_meet else 0.6 for y in between],
                                     transform=across), autolim=False)
    if zero:
        ax.add_collection(LineCollection([[(0.0, lane.height(0.0, m)), (1.0, lane.height(0.0, m))]
                                          for lane, m in zip(drawn, mids, strict=True)],
                                         colors="0.6", lw=0.6, linestyles=":",
                                         transform=across), autolim=False)
    for lane, m in zip(drawn, mids, strict=True):
        ax.text(-0.012, m, lane.label, transform=across, ha="right", va="center",
                fontsize=7, gid=f"label:{lane.name}")
    side = -(LABEL_WIDTH - 0.12) / (ax.get_position().width * ax.figure.get_size_inches()[0])
    first = 0
    for (_, arm, colour), count in zip(ARMS, counts, strict=True):
        if count:
            ax.text(side, middle(first, lanes) - 0.5 * (count - 1), arm, transform=across,
                    rotation=90, ha="center", va="center", fontsize=8, color=colour)
        first += count


def draw_lane(ax: Any, lane: Lane, k: int, lanes: int, t: Any,
              traces: Sequence[tuple[Any, Any, dict[str, Any]]], outside: Any) -> None:
    """Draw one lane: its limits, its traces and the time spent outside them.

    Parameters
    ----------
    ax : Axes
        The lane axis.
    lane : Lane
        The lane (its limits, its scale).
    k, lanes : int
        The lane's index (0-based, from the top) and the lanes in the axis.
    t : array_like
        Sample times [s] (of the shading).
    traces : sequence of (times, values, style)
        The lines drawn: times [s], values in display units, keyword arguments of
        ``plot`` (a ``gid`` among them).
    outside : array_like of bool
        The samples shaded (beyond a limit).

    The limits are one line collection (gid ``limit:<name>``), the shading one
    collection of bars across the lane (gid ``outside:<name>``).
    """
    mid = middle(k, lanes)
    if lane.limits:
        lines = LineCollection([[(0.0, y), (1.0, y)] for y in
                                (lane.height(v, mid) for v in lane.limits)],
                               colors=LIMIT_COLOUR, linestyles="--", lw=0.8,
                               transform=ax.get_yaxis_transform())
        lines.set_gid(f"limit:{lane.name}")
        ax.add_collection(lines, autolim=False)
    for times, values, style in traces:
        ax.plot(times, lane.scale(values, mid), **style)
    spans = outside_spans(t, outside)
    if spans:
        bars = ax.broken_barh([(a, b - a) for a, b in spans], (mid - 0.5, 1.0),
                              color=LIMIT_COLOUR, alpha=0.15, lw=0)
        bars.set_gid(f"outside:{lane.name}")


def _counts(data: RunData) -> tuple[int, int]:
    """Return the leader's and the follower's joint counts."""
    return data.n_joints("l"), data.n_joints("f")


def _title(fig: Figure, title: str, text: str) -> None:
    fig.suptitle((title + ": " if title else "") + text, fontsize=10,
                 y=1.0 - 0.12 / fig.get_size_inches()[1], va="top")


def joints_figure(data: RunData, limits: PlotLimits, title: str = "") -> Figure:
    """Both arms' joints against their ranges, one lane per joint, outside shaded.

    Angles in the file's unit (deg or rad), named in the title. Each trace's gid is
    ``joint:<column>``; each lane's label's ``label:<column>``.
    """
    counts = _counts(data)
    lanes = max(sum(counts), 1)
    fig, (ax,) = lane_axes(1, lanes, top=0.45, bottom=0.5, ahead="lanes:joints")
    t = data.t
    per_rad = limits.units.per_rad
    drawn: list[Lane] = []
    for arm, _, colour in ARMS:
        q = data.joints(arm)
        lim = limits.arm(arm)
        for j in range(q.shape[1]):
            name = f"q{arm}{j + 1}"
            values = q[:, j] * per_rad
            lane = range_lane(name, f"q{j + 1}", values, lim.q_min[j] * per_rad,
                              lim.q_max[j] * per_rad)
            draw_lane(ax, lane, len(drawn), lanes, t,
                      [(t, values, {"color": colour, "lw": 1.1, "gid": f"joint:{name}"})],
                      outside_mask(q[:, j], lim.q_min[j], lim.q_max[j]))
            drawn.append(lane)
    label_lanes(ax, drawn, counts)
    _title(fig, title, f"joints against their ranges [{limits.units.angle}] "
                       "(dashed; shaded: outside)")
    return fig


def _rate_lanes(ax: Any, t: Any, arms: Sequence[tuple[Any, Any, Any, str]], *,
                per_rad: float, counts: Sequence[int], colour: str = "C1") -> None:
    """Draw both arms' rate lanes in ``ax``.

    ``arms`` holds, per arm, the commanded rates (None for accelerations and jerks),
    the realised values [rad/s, rad/s^2 or rad/s^3], their limits and the columns'
    pattern (``"qf_dot{}"``). ``colour`` is the realised values' (dotted beside the
    commanded rates, solid alone).
    """
    lanes = sum(counts)
    drawn: list[Lane] = []
    for commanded, realised, maxima, name in arms:
        for j in range(realised.shape[1]):
            column = name.format(j + 1)
            vmax = float(maxima[j])
            traces: list[tuple[Any, Any, dict[str, Any]]] = []
            if commanded is not None:  # the last row's command is never applied: left out
                traces.append((t[:-1], commanded[:-1, j] * per_rad,
                               {"color": "C0", "lw": 1.0, "gid": f"commanded:{column}"}))
            traces.append((t, realised[:, j] * per_rad,
                           {"color": colour, "lw": 0.9,
                            "ls": ":" if commanded is not None else "-",
                            "gid": f"realised:{column}"}))
            lane = speed_lane(column, f"q{j + 1}", [v for _, v, _ in traces],
                              vmax * per_rad)
            draw_lane(ax, lane, len(drawn), lanes, t, traces,
                      outside_mask(realised[:, j], -vmax, vmax))
            drawn.append(lane)
    label_lanes(ax, drawn, counts, zero=True)


#: The derivatives of the rates a run may limit: their name, columns' letters, colour
#: and the power of the unit's seconds.
DERIVATIVES = {"acceleration": ("ddot", "C4", "\N{SUPERSCRIPT TWO}"),
               "jerk": ("dddot", "C5", "\N{SUPERSCRIPT THREE}")}


def _derivative_lanes(ax: Any, data: RunData, limits: PlotLimits, kind: str,
                      counts: Sequence[int]) -> None:
    """Draw both arms' realised accelerations or jerks against their limits in ``ax``."""
    letters, colour, _ = DERIVATIVES[kind]
    rows = []
    for arm, _, _ in ARMS:
        value = (data.realised_accelerations(arm) if kind == "acceleration"
                 else data.realised_jerks(arm))
        lim = limits.arm(arm)
        given = lim.qdd_max if kind == "acceleration" else lim.qddd_max
        rows.append((None, value, given if given is not None
                     else np.full(value.shape[1], np.inf), f"q{arm}_{letters}{{}}"))
    _rate_lanes(ax, data.t, rows, per_rad=limits.units.per_rad, counts=counts, colour=colour)


def rates_figure(data: RunData, limits: PlotLimits, title: str = "") -> Figure:
    """Joint rates against the speed limits (and accelerations, jerks against theirs).

    Angles in the file's unit (deg or rad) per second (per second squared, cubed),
    named in the titles.

    The realised rate is the finite difference of the recorded joints; it differs
    from the commanded one where a position-level correction moved the joints. The
    shading marks the samples whose realised rate is over the limit. The last row's
    command, computed but never applied, is left out. When the run kept acceleration
    limits, an axis beside the first shows the realised accelerations (finite
    differences of the realised rates, the first from rest) against ``qdd_max``; when it
    kept jerk limits, one more the realised jerks (the accelerations' differences)
    against ``qddd_max``. Traces carry the gids ``commanded:<column>`` and
    ``realised:<column>``.
    """
    blocks = [b for b, on in (("acceleration", limits.acceleration_limits_enforced),
                              ("jerk", limits.jerk_limits_enforced)) if on]
    counts = _counts(data)
    lanes = max(sum(counts), 1)
    fig, axes = lane_axes(1 + len(blocks), lanes, top=0.7 if blocks else 0.45, bottom=0.8,
                          ahead="lanes:rates")
    per_rad, unit = limits.units.per_rad, limits.units.angle
    _rate_lanes(axes[0], data.t, [(data.commanded_rates(arm), data.realised_rates(arm),
                                   limits.arm(arm).qd_max, f"q{arm}_dot{{}}")
                                  for arm, _, _ in ARMS], per_rad=per_rad, counts=counts)
    for ax, block in zip(axes[1:], blocks, strict=True):
        _derivative_lanes(ax, data, limits, block, counts)
        panel_title(ax, f"realised {block}s [{unit}/s{DERIVATIVES[block][2]}]", fontsize=9)
    if blocks:
        panel_title(axes[0], f"rates [{unit}/s]", fontsize=9)
    _legend(fig, limits, blocks)
    _title(fig, title, "joint rates against their speed limits (dashed)"
           + ("".join(f"; {b}s against theirs" for b in blocks) if blocks
              else f" [{unit}/s]"))
    return fig


def _legend(fig: Figure, limits: PlotLimits, blocks: Sequence[str]) -> None:
    """One legend under the axes: the traces, the limit lines and the shading."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    speed = ("speed limit" if limits.speed_limits_enforced
             else "speed limit (not enforced in this run)")
    handles: list[Any] = [Line2D([], [], color="C0", lw=1.0),
                          Line2D([], [], color="C1", lw=0.9, ls=":")]
    labels = ["commanded", "realised"]
    for block in blocks:
        handles.append(Line2D([], [], color=DERIVATIVES[block][1], lw=0.9))
        labels.append(f"realised {block}")
    handles += [Line2D([], [], color=LIMIT_COLOUR, ls="--", lw=0.8),
                Patch(color=LIMIT_COLOUR, alpha=0.15, lw=0)]
    labels += [", ".join([speed, *(f"{b} limit" for b in blocks)]),
               "realised over the limit"]
    fig.legend(handles, labels, loc="lower center", ncol=len(labels), fontsize=7,
               frameon=False)


__all__ = ["CLIP", "LIMIT", "Lane", "joints_figure", "range_lane", "rates_figure", "speed_lane"]
