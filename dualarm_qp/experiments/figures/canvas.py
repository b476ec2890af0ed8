"""Drawing primitives shared by every figure: the canvas, limit lines, shaded spans.

Figures are drawn with matplotlib's object interface (:class:`~matplotlib.figure.Figure`
on an Agg canvas), never through :mod:`matplotlib.pyplot`: drawing leaves the user's
backend choice and pyplot's figures alone. Values arrive in SI units; the callers pass
the factor that converts them for display (mm, deg) at drawing time.

Artists carry a ``gid`` saying what they show (``"limit:<name>"``, ``"outside:<name>"``)
so that tests, and anyone post-processing a figure, can find them.
"""

from __future__ import annotations

import io
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.ticker import FuncFormatter, Locator, LogLocator, MaxNLocator, NullLocator
from numpy.typing import NDArray
from PIL import Image

from ..._io import atomic_write_with

FloatArray = NDArray[np.float64]

#: Resolution of the PNG files [dots per inch].
DPI = 110

#: Colours in a PNG's palette (a figure uses fewer than this: its lines' colours, the
#: shading, the text and their anti-aliased edges).
PALETTE = 256

#: Pillow's fast octree quantisation and no dithering (their values in Pillow < 9.1,
#: which has no enums for them).
_FAST_OCTREE: Any = getattr(getattr(Image, "Quantize", None), "FASTOCTREE", 2)
_NO_DITHER: Any = getattr(getattr(Image, "Dither", None), "NONE", 0)

#: Colour of limit lines and of the shading of samples outside their range.
LIMIT_COLOUR = "C3"


def new_figure(**kwargs: Any) -> Figure:
    """Return a figure on its own Agg canvas (no pyplot, no global state)."""
    fig = Figure(**kwargs)
    FigureCanvasAgg(fig)
    return fig


def fixed_margins(fig: Figure, *, left: float = 0.9, right: float = 0.2, top: float = 0.45,
                  bottom: float = 0.5, hspace: float = 0.2, wspace: float = 0.2) -> None:
    """Place the axes with fixed margins [in] around them.

    ``tight_layout`` measures every tick label of every axis before it places them,
    which costs more than drawing the figure; the figures of a run have the same
    labels every time, so their margins are fixed. ``hspace`` and ``wspace`` are the
    gaps between axes, as fractions of the average axis height and width.
    """
    width, height = fig.get_size_inches()
    fig.subplots_adjust(left=left / width, right=1.0 - right / width, top=1.0 - top / height,
                        bottom=bottom / height, hspace=hspace, wspace=wspace)


def panel_title(ax: Any, text: str, **kwargs: Any) -> None:
    """Title an axis, just above its top edge.

    The title's height is given (not found by measuring the tick labels above the
    axis, of which a run's figures have none), which saves most of the cost of
    drawing a small panel.
    """
    ax.set_title(text, y=1.0, **kwargs)


#: At most this many intervals between the ticks of an axis of a run's figures: each
#: tick is several artists, and the ticks are much of a figure's drawing cost.
TICKS = 5


def few_ticks(ax: Any) -> None:
    """Give both axes of ``ax`` at most :data:`TICKS` intervals between round ticks.

    Call it before an axis is made logarithmic (:func:`log_y`) or given its own ticks
    (:func:`speed_axis`), which replace it on that axis.
    """
    ax.xaxis.set_major_locator(InView(MaxNLocator(nbins=TICKS, steps=[1, 2, 2.5, 5, 10])))
    ax.yaxis.set_major_locator(InView(MaxNLocator(nbins=TICKS, steps=[1, 2, 2.5, 5, 10])))


def shared_time(axes: Sequence[Any]) -> None:
    """Let a column of axes that share their time axis tick it on the bottom one only.

    The others have no x ticks at all (rather than ticks without labels): a tick is
    several artists, drawn or not.
    """
    for ax in axes[:-1]:
        ax.xaxis.set_visible(False)


class InView(Locator):
    """The ticks of another locator that lie in the axis's view, and no others.

    matplotlib's locators also give a tick beyond each end of the view, which the axis
    makes (several artists each) and never draws.

    Parameters
    ----------
    base : Locator
        The locator whose ticks are kept.
    """

    def __init__(self, base: Locator) -> None:
        self.base = base

    def set_axis(self, axis: Any) -> None:
        """Attach this locator, and its base, to ``axis``."""
        super().set_axis(axis)
        self.base.set_axis(axis)

    def __call__(self) -> list[float]:
        """Return the base's ticks inside the view (its ends included, within rounding)."""
        if self.axis is None:  # not on an axis yet: no view to keep ticks in
            return []
        lo, hi = sorted(float(v) for v in self.axis.get_view_interval())
        slack = 1e-9 * (hi - lo)
        return [float(v) for v in self.base() if lo - slack <= v <= hi + slack]

    def tick_values(self, vmin: float, vmax: float) -> Any:
        """Return the base's ticks for the interval ``[vmin, vmax]``."""
        return self.base.tick_values(vmin, vmax)


#: Unicode superscripts for the powers of ten on log axes.
_SUPERSCRIPTS = str.maketrans("-0123456789", "\N{SUPERSCRIPT MINUS}\u2070\u00b9\u00b2\u00b3"
                              "\u2074\u2075\u2076\u2077\u2078\u2079")


def power_text(value: float, _pos: Any = None) -> str:
    """Return the label of a log-axis tick: ``10⁻⁹`` for a power of ten, else nothing.

    The same text as matplotlib's own labels, written with Unicode superscripts
    instead of its mathematical typesetting (which parses each label anew).
    """
    if not value > 0:
        return ""
    power = float(np.log10(value))
    if abs(power - round(power)) > 1e-9:
        return ""
    return "10" + str(round(power)).translate(_SUPERSCRIPTS)


def log_y(ax: Any) -> None:
    """Make the y axis of ``ax`` logarithmic, its powers of ten labelled by :func:`power_text`.

    Without minor ticks: on axes spanning six decades and more, as the error axes do,
    they are a dense hatching that costs more to draw than the rest of the figure. At
    most :data:`TICKS` + 1 major ticks (every other power of ten on a long axis).
    """
    ax.set_yscale("log")
    ax.yaxis.set_major_locator(InView(LogLocator(numticks=TICKS + 1)))
    ax.yaxis.set_major_formatter(FuncFormatter(power_text))
    ax.yaxis.set_minor_locator(NullLocator())


def _write_png(fig: Figure, target: Any) -> None:
    """Draw ``fig`` at :data:`DPI` and write it to ``target`` (a path or a file) as a PNG.

    The figures are opaque (a white background) line drawings of a few colours and
    their anti-aliased edges, so the PNG holds a palette of :data:`PALETTE` colours
    (quantised without dithering) rather than four channels: the same picture to the
    eye, in a quarter of the bytes, compressed in less time.
    """
    fig.set_dpi(DPI)
    canvas = fig.canvas if isinstance(fig.canvas, FigureCanvasAgg) else FigureCanvasAgg(fig)
    canvas.draw()
    width, height = canvas.get_width_height(physical=True)
    rgba = Image.frombuffer("RGBA", (width, height), canvas.buffer_rgba(), "raw", "RGBA", 0, 1)
    rgba.convert("RGB").quantize(colors=PALETTE, method=_FAST_OCTREE, dither=_NO_DITHER).save(
        target, format="png", dpi=(DPI, DPI))


def save_png(fig: Figure, path: Path) -> None:
    """Write ``fig`` to ``path`` as a PNG, atomically."""
    atomic_write_with(path, lambda tmp: _write_png(fig, tmp))


def png_bytes(fig: Figure) -> bytes:
    """Return ``fig`` rendered as PNG bytes."""
    buf = io.BytesIO()
    _write_png(fig, buf)
    return buf.getvalue()


def outside_mask(y: Any, lo: float = -np.inf, hi: float = np.inf, *,
                 tol: float = 1e-9) -> NDArray[np.bool_]:
    """Flag the samples of ``y`` outside ``[lo - tol, hi + tol]`` (NaN counts as inside).

    Parameters
    ----------
    y : array_like
        Values, in the units of the bounds.
    lo, hi : float
        The range; infinite bounds never hold anything out.
    tol : float
        Slack, in the units of ``y``, so that a value held exactly at a bound by a
        hard-limit solver (rounding included) is not shaded.
    """
    v = np.asarray(y, dtype=float)
    with np.errstate(invalid="ignore"):
        return np.asarray((v < lo - tol) | (v > hi + tol))


def outside_spans(t: Any, outside: Any) -> list[tuple[float, float]]:
    """Time intervals [s] covering the runs of consecutive samples flagged ``outside``.

    A run from sample ``i`` to sample ``j`` covers ``[t_i - h, t_j + h]`` with ``h`` half
    the sampling interval (clipped to the sampled time), so that a single sample
    outside is still a visible band.

    Parameters
    ----------
    t : array_like, shape (n,)
        Sample times [s], increasing.
    outside : array_like of bool, shape (n,)
        Which samples are outside.

    Returns
    -------
    list of (float, float)
        ``(start, end)`` [s] of each run, in time order.
    """
    t = np.asarray(t, dtype=float)
    flags = np.asarray(outside, dtype=bool)
    if t.size == 0 or not flags.any():
        return []
    half = 0.5 * float(np.median(np.diff(t))) if t.size > 1 else 0.0
    edges = np.diff(np.concatenate(([0], flags.astype(np.int8), [0])))
    starts = np.flatnonzero(edges == 1)
    ends = np.flatnonzero(edges == -1) - 1
    return [(max(float(t[i]) - half, float(t[0])), min(float(t[j]) + half, float(t[-1])))
            for i, j in zip(starts, ends, strict=True)]


def shade_spans(ax: Any, spans: Sequence[tuple[float, float]], name: str, *,
                colour: str = LIMIT_COLOUR, alpha: float = 0.15,
                label: str | None = None) -> list[Any]:
    """Shade the time intervals ``spans`` on ``ax`` (gid ``"outside:<name>"``).

    ``label`` goes on the first band only (one legend entry).
    """
    patches = []
    for k, (a, b) in enumerate(spans):
        patch = ax.axvspan(a, b, color=colour, alpha=alpha, lw=0,
                           label=label if k == 0 else None)
        patch.set_gid(f"outside:{name}")
        patches.append(patch)
    return patches


def limit_lines(ax: Any, values: Sequence[float], name: str, *, scale: float = 1.0,
                colour: str = LIMIT_COLOUR, label: str | None = None,
                ls: str = "--") -> list[Any]:
    """Draw the finite ``values`` (SI) times ``scale`` as horizontal lines.

    Each line's gid is ``"limit:<name>"``; ``label`` goes on the first line only.
    """
    lines: list[Any] = []
    for v in values:
        if v is None or not np.isfinite(v):
            continue
        line = ax.axhline(float(v) * scale, color=colour, ls=ls, lw=0.9,
                          label=label if not lines else None)
        line.set_gid(f"limit:{name}")
        lines.append(line)
    return lines


def tick_text(value: float) -> str:
    """Return a tick label a person reads: ``0``, ``0.05``, ``50``, ``1,000``, ``-10,000``.

    Positional notation (never ``1e+03``), thousands separated, a true minus sign (as
    matplotlib's own labels).
    """
    if value == 0:
        return "0"
    size = abs(float(value))
    text = (f"{size:,.0f}" if size >= 1000
            else np.format_float_positional(size, precision=4, trim="-"))
    return ("\N{MINUS SIGN}" if value < 0 else "") + text


def round_ticks(top: float, bins: int = 3) -> list[float]:
    """Round numbers (1, 2, 2.5 or 5 times a power of ten) from 0 up to ``top`` > 0."""
    values = MaxNLocator(nbins=bins, steps=[1, 2, 2.5, 5, 10]).tick_values(0.0, top)
    return [float(v) for v in values if 0.0 <= v <= top * (1 + 1e-9)]


def speed_axis(ax: Any, limit: float | None, peak: float) -> None:
    """Scale the y axis of a speed panel against its limit (display units).

    When the largest ``|speed|`` (``peak``) stays within ``1.05 * limit`` the axis is
    linear over ``+-1.15 * limit``: the data read against the limit. When it goes
    beyond (the unbounded first step of the paper's method, thousands of times the
    limit), the axis is symmetric-logarithmic, linear inside ``+-limit``, so that one
    huge sample does not squeeze everything else to a line. Without a finite,
    positive limit the threshold is the power of ten nearest ``peak / 100`` (linear
    when ``peak`` is 0).

    The ticks are round numbers in the display units (:func:`round_ticks`): a few
    inside the limit, then the powers of ten from three times the limit (or one of 2
    or 5 times a power of ten when none fits), labelled by :func:`tick_text`. The limit
    itself is the dashed line, named in the legend.
    """
    lin = float(limit) if limit is not None and np.isfinite(limit) and limit > 0 else 0.0
    if lin and peak <= 1.05 * lin:
        ax.set_ylim(-1.15 * lin, 1.15 * lin)
        return
    if not lin:
        if not peak > 0:
            return
        lin = float(10.0 ** np.round(np.log10(peak / 100.0)))
    ax.set_yscale("symlog", linthresh=lin, linscale=1.5)
    top = 1.6 * peak
    exponents = np.arange(np.floor(np.log10(lin)), np.ceil(np.log10(top)) + 1)
    outer = [10.0 ** e for e in exponents if 3.0 * lin <= 10.0 ** e <= top]
    if not outer:  # no power of ten fits: one of 2 or 5 times one
        outer = [m * 10.0 ** e for e in exponents for m in (2.0, 5.0)
                 if 3.0 * lin <= m * 10.0 ** e <= top][:1]
    half = [*round_ticks(lin), *outer]
    ticks = sorted({-v for v in half} | set(half))
    ax.set_yticks(ticks, [tick_text(v) for v in ticks])
    ax.yaxis.set_minor_locator(NullLocator())
    ax.set_ylim(-top, top)


def log_axis(ax: Any, levels: Sequence[float], values: Sequence[Any], *,
             decades: float) -> float:
    """Limit a log y axis to the scale that matters, and return its bottom.

    The axis runs from ``decades`` below the smallest of the ``levels`` that matter
    (tolerances, thresholds; without one, the largest value) to above the largest level
    or value. Draw the values through ``np.maximum(values, bottom)``: smaller ones
    (exact zeros, rounding at 1e-16) lie on the bottom edge instead of stretching the
    axis down to them, and :func:`note_bottom` says so in the legend.

    Parameters
    ----------
    ax : Axes
        A log-scaled y axis.
    levels : sequence of float
        The lines the data are read against (non-positive ones are ignored).
    values : sequence of array_like
        The data drawn (NaN ignored).
    decades : float
        How far below the smallest level the axis goes (powers of ten).
    """
    data = [np.asarray(v, dtype=float).ravel() for v in values]
    finite = np.concatenate([d[np.isfinite(d)] for d in data]) if data else np.zeros(0)
    marks = [float(v) for v in levels if v is not None and np.isfinite(v) and v > 0]
    positive = finite[finite > 0]
    reference = min(marks) if marks else float(positive.max()) if positive.size else 1.0
    bottom = float(10.0 ** (np.floor(np.log10(reference)) - decades))
    high = max([*marks, float(positive.max()) if positive.size else reference])
    ax.set_ylim(bottom, float(10.0 ** np.ceil(np.log10(2.0 * high))))
    return bottom


def note_bottom(ax: Any, bottom: float, values: Sequence[Any]) -> None:
    """Add a legend entry saying that values below ``bottom`` lie on the bottom edge.

    Only when some of the ``values`` (array_like, NaN ignored) are below it.
    """
    low = [np.nanmin(a) for a in (np.asarray(v, dtype=float) for v in values)
           if a.size and np.isfinite(a).any()]
    if low and min(low) < bottom:
        power = f"1e{round(np.log10(bottom))}" if bottom > 0 else f"{bottom:g}"
        ax.plot([], [], color="none", label=f"below {power}: on the bottom edge")


def finite_max_abs(*arrays: Any) -> float:
    """Largest finite absolute value in the arrays (0 if none)."""
    best = 0.0
    for a in arrays:
        v = np.abs(np.asarray(a, dtype=float))
        v = v[np.isfinite(v)]
        if v.size:
            best = max(best, float(v.max()))
    return best
