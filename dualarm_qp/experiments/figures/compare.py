"""One quantity of several runs side by side: the reproduction's Figs. 5 and 6.

A comparison figure has four panels: the quantity over the whole run and zoomed on its
first moments (where the paper's unbounded first step jumps), and its realised rate
(finite differences of the recorded samples) over the same two windows, against the
speed limit of the hard-limit run. Samples outside the range are shaded in the colour
of their run.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from matplotlib.figure import Figure
from numpy.typing import NDArray

from .canvas import (
    finite_max_abs,
    fixed_margins,
    limit_lines,
    new_figure,
    outside_mask,
    outside_spans,
    panel_title,
    shade_spans,
    speed_axis,
    tick_text,
)
from .rundata import realised_rate

FloatArray = NDArray[np.float64]

#: Length of the zoomed window at the start [s].
ZOOM_S = 0.5

#: The figure's height, the room for its title and the height of one line of a legend
#: or of the note at 7 points [in].
HEIGHT, TITLE_IN, LINE_IN = 7.2, 0.4, 0.16


@dataclass(frozen=True)
class Curve:
    """One run's samples of the compared quantity.

    Attributes
    ----------
    label : str
        Legend text.
    t : ndarray, shape (n,)
        Sample times [s].
    value : ndarray, shape (n,)
        The quantity, SI units.
    colour : str
        Matplotlib colour.
    """

    label: str
    t: FloatArray
    value: FloatArray
    colour: str


def _view(values: Sequence[FloatArray], extra: Sequence[float] = ()) -> tuple[float, float]:
    """Return a padded y-range spanning the finite values and the ``extra`` levels."""
    parts = [v[np.isfinite(v)] for v in values] + [np.asarray(extra, dtype=float)]
    allv = np.concatenate([p for p in parts if p.size]) if any(p.size for p in parts) \
        else np.zeros(1)
    lo, hi = float(allv.min()), float(allv.max())
    pad = 0.08 * max(hi - lo, 1e-9)
    return lo - pad, hi + pad


def _number(value: float, unit: str) -> str:
    """Return a value for a legend, to 4 digits, with its unit (``"114.6 deg"``)."""
    return f"{tick_text(float(f'{value:.4g}'))} {unit}".strip()


def range_label(near: Sequence[float], far: Sequence[tuple[str, float, str]],
                unit: str) -> str:
    """Legend text of the range limits on an axis (display units).

    Parameters
    ----------
    near : sequence of float
        The limits drawn (dashed).
    far : sequence of (str, float, str)
        ``(which, value, where)`` of each limit left out because it lies far from the
        data: ``which`` is ``"lower"`` or ``"upper"``, ``where`` ``"above"`` or
        ``"below"`` the axis.
    unit : str
        Display unit.
    """
    drawn = " and ".join(_number(v, "") for v in near)
    if not far:
        return f"range limit{'s' if len(near) > 1 else ''} {drawn} {unit}".rstrip()
    away = "; ".join(f"the {which} limit, {_number(v, unit)}, is far {where} the axis"
                     for which, v, where in far)
    if not near:
        return f"range limits off the axis: {away}"
    return f"range limit {drawn} {unit} ({away})"


def _range_panel(ax: Any, curves: Sequence[Curve], value_range: tuple[float, float],
                 scale: float, unit: str, name: str, window: tuple[float, float] | None
                 ) -> None:
    """Draw the values, the range limits near them, and the outside shading."""
    lo_r, hi_r = value_range
    shown_vals = []
    for c in curves:
        keep = np.ones(c.t.shape, dtype=bool) if window is None else \
            (c.t >= window[0]) & (c.t <= window[1])
        ax.plot(c.t, c.value * scale, color=c.colour, label=c.label,
                marker="." if window is not None else None, ms=4, lw=1.2)
        shade_spans(ax, outside_spans(c.t, outside_mask(c.value, lo_r, hi_r)),
                    f"{name}:{c.label}", colour=c.colour, alpha=0.15)
        shown_vals.append(c.value[keep] * scale)
    # A range limit far outside the data is named in the legend, not drawn: it would
    # squeeze the curves (Fig. 5: q3's upper limit, 225 deg, against data below 7 deg).
    lo, hi = _view(shown_vals)
    span = hi - lo
    near, far = [], []
    for which, v in (("lower", lo_r), ("upper", hi_r)):
        if not np.isfinite(v):
            continue
        shown = v * scale
        if lo - 0.5 * span <= shown <= hi + 0.5 * span:
            near.append(shown)
        else:
            far.append((which, shown, "above" if shown > hi else "below"))
    label = range_label(near, far, unit) if near or far else None
    limit_lines(ax, near, name, label=label if near else None)
    if far and not near:
        ax.plot([], [], color="none", label=label)
    ax.set_ylim(*_view(shown_vals, near))
    if window is not None:
        ax.set_xlim(*window)


def _speed_panel(ax: Any, curves: Sequence[Curve], speed_limit: float | None, scale: float,
                 unit: str, name: str, window: tuple[float, float] | None) -> None:
    """Draw the realised rates, the speed limit and the over-the-limit shading."""
    vmax = float(speed_limit) if speed_limit is not None else np.inf
    peak = 0.0
    for c in curves:
        rate = realised_rate(c.t, c.value)
        keep = np.ones(c.t.shape, dtype=bool) if window is None else \
            (c.t >= window[0]) & (c.t <= window[1])
        peak = max(peak, finite_max_abs(rate[keep]) * abs(scale))
        ax.plot(c.t, rate * scale, color=c.colour, lw=1.1,
                marker="." if window is not None else None, ms=4)
        shade_spans(ax, outside_spans(c.t, outside_mask(rate, -vmax, vmax)),
                    f"{name}:{c.label}", colour=c.colour, alpha=0.15)
    if np.isfinite(vmax):
        limit_lines(ax, (-vmax, vmax), name, scale=scale,
                    label=f"speed limit \N{PLUS-MINUS SIGN}{_number(vmax * abs(scale), unit)}/s")
    speed_axis(ax, vmax * abs(scale), peak)
    if window is not None:
        ax.set_xlim(*window)


def comparison_figure(curves: Sequence[Curve], *, value_range: tuple[float, float],
                      speed_limit: float | None, scale: float, value_label: str,
                      speed_label: str, title: str, zoom: float = ZOOM_S,
                      note: str = "", unit: str = "") -> Figure:
    """Draw one quantity of several runs: whole run and first ``zoom`` seconds.

    Parameters
    ----------
    curves : sequence of Curve
        The runs, SI units.
    value_range : (float, float)
        The quantity's range (SI); samples outside are shaded in the run's colour.
    speed_limit : float or None
        Limit on the quantity's rate (SI per second), drawn as dashed lines; the rate
        axes are symmetric-logarithmic, linear inside it.
    scale : float
        SI to display units (e.g. ``1e3`` for mm, ``180/pi`` for deg).
    value_label, speed_label : str
        Axis labels, with the display units.
    title : str
        Figure title.
    zoom : float
        Length of the zoomed window [s] from the first sample.
    note : str
        Small print under the axes.
    unit : str
        The display unit of the quantity (``"deg"``, ``"mm"``), for the legends.

    Returns
    -------
    Figure
        Axes ``[[value, value zoomed], [rate, rate zoomed]]``; limit lines carry the
        gid ``"limit:range"`` / ``"limit:speed"`` and shaded spans
        ``"outside:range:<label>"`` / ``"outside:speed:<label>"``.
    """
    fig = new_figure(figsize=(11, HEIGHT))
    axes = fig.subplots(2, 2, gridspec_kw={"width_ratios": (2.2, 1)})
    t0 = min((float(c.t[0]) for c in curves if c.t.size), default=0.0)
    dts = [float(np.median(np.diff(c.t))) for c in curves if c.t.size > 1]
    half = 0.5 * min(dts) if dts else 0.0
    window = (t0 - half, t0 + zoom)
    _range_panel(axes[0][0], curves, value_range, scale, unit, "range", None)
    _range_panel(axes[0][1], curves, value_range, scale, unit, "range", window)
    _speed_panel(axes[1][0], curves, speed_limit, scale, unit, "speed", None)
    _speed_panel(axes[1][1], curves, speed_limit, scale, unit, "speed", window)
    axes[0][0].set_ylabel(value_label)
    axes[1][0].set_ylabel(speed_label)
    panel_title(axes[0][1], f"first {zoom:g} s", fontsize=9)
    panel_title(axes[1][1], f"first {zoom:g} s", fontsize=9)
    for ax in axes[1]:
        ax.set_xlabel("t [s]")
    # One legend for the figure, under the title: the runs, the range, the speed limit
    # (inside a panel it would hide the curves).
    handles, labels = axes[0][0].get_legend_handles_labels()
    more, more_labels = axes[1][0].get_legend_handles_labels()
    ncol = 2
    rows = -(-(len(labels) + len(more_labels)) // ncol)
    fig.legend([*handles, *more], [*labels, *more_labels], loc="upper center",
               bbox_to_anchor=(0.5, 1.0 - TITLE_IN / HEIGHT), ncol=ncol, fontsize=7,
               frameon=False)
    fig.suptitle(title, fontsize=10)
    top = TITLE_IN + LINE_IN * rows + 0.35
    bottom = 0.6 + (LINE_IN * (note.count("\n") + 1) if note else 0.0)
    fixed_margins(fig, left=1.0, right=0.25, top=top, bottom=bottom, hspace=0.3, wspace=0.15)
    if note:
        fig.text(0.01, 0.012, note, fontsize=7, color="0.3")
    return fig
