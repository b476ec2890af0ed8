"""Figures of a sweep's table: maps over two swept keys, curves over one.

Each function takes the table's rows (dicts by column), the swept keys and their axis
labels (:mod:`.labels`) and returns a :class:`matplotlib.figure.Figure` on its own Agg
canvas (no pyplot, no global state).
A swept key whose values are all numbers is a numeric axis; any other key is an axis of
categories in the order they first come in the table (a grid key's: the sweep file's).
Points that share the two mapped values (other keys swept too) are summed up per cell:
the mean completion, the worst ratio, the smallest margin. Every sampled place is marked
by the outcome of its points (completed, failed, start unreachable, interrupted; the
worst where several points share it), the axes span the sampled values (and a small
margin), and a grid of few values along a key is drawn as squares at the places rather
than as cells, which would fill the axes as one block. The markers are explained in one
legend below the axes, off the cells.
"""

from __future__ import annotations

import math
from collections import defaultdict
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import TwoSlopeNorm
from matplotlib.figure import Figure

from .points import START_UNREACHABLE

#: Most distinct values of a numeric key drawn one by one; more are binned.
MAX_LEVELS = 12

#: Legend of the points whose start cannot be reached (crossed out on the maps).
UNREACHABLE_LABEL = "start unreachable"

#: Legend of the points that ran but never got inside every range (circled).
NEVER_INSIDE_LABEL = "never inside every range"

#: The marker of each outcome of a point: (matplotlib marker, fill, size [pt]), the
#: worst first. A place where several points lie (other keys swept too) shows the worst.
OUTCOMES = {
    UNREACHABLE_LABEL: ("X", "black", 8.0),
    "failed": ("v", "black", 7.0),
    "interrupted": ("P", "0.6", 7.0),
    "completed": ("o", "white", 5.5),
}

#: A full grid is drawn as cells from this many values along each of its two keys; a
#: smaller one as squares at the sampled places.
MIN_CELL_LEVELS = 4

#: The maps' axes go this share of the sampled span beyond the outer samples (numbers).
MARGIN = 0.08

#: ... and at least this far, in steps between categories, for an axis of categories.
CATEGORY_MARGIN = 0.4

#: The swept key of the solver's name.
SOLVER_KEY = "solver.name"

Rows = Sequence[dict[str, Any]]

#: Axis label of each swept key (a key left out is labelled by itself).
Labels = Mapping[str, str]


def _figure(**kwargs: Any) -> Figure:
    fig = Figure(**kwargs)
    FigureCanvasAgg(fig)
    return fig


def _finite(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) \
        and math.isfinite(value)


def _is_numeric(values: Sequence[Any]) -> bool:
    return bool(values) and all(_finite(v) for v in values)


class _Axis:
    """Positions of a swept key's values on a plot axis."""

    def __init__(self, key: str, values: Sequence[Any], label: str | None = None) -> None:
        self.key = key
        self.text = label or key
        self.numeric = _is_numeric(values)
        self.levels: list[Any] = (sorted(set(values)) if self.numeric
                                  else list(dict.fromkeys(values)))

    def pos(self, value: Any) -> float:
        return float(value) if self.numeric else float(self.levels.index(value))

    def edges(self) -> np.ndarray:
        """Cell edges around each level (midpoints; half a step beyond the ends)."""
        p = np.array([self.pos(v) for v in self.levels], dtype=float)
        if len(p) == 1:
            return np.array([p[0] - 0.5, p[0] + 0.5])
        mid = (p[1:] + p[:-1]) / 2
        return np.concatenate([[p[0] - (mid[0] - p[0])], mid, [p[-1] + (p[-1] - mid[-1])]])

    def label(self, ax: Any, which: str) -> None:
        getattr(ax, f"set_{which}label")(self.text)
        if not self.numeric:
            getattr(ax, f"set_{which}ticks")(range(len(self.levels)),
                                             [str(v) for v in self.levels])


def _cells(rows: Rows, kx: str, ky: str, metric: Callable[[dict[str, Any]], float],
           agg: Callable[[list[float]], float]) -> dict[tuple[Any, Any], float]:
    """Return the metric summed up per (x, y) value pair (points with no number left out)."""
    groups: dict[tuple[Any, Any], list[float]] = defaultdict(list)
    for r in rows:
        v = metric(r)
        if _finite(v):
            groups[(r[kx], r[ky])].append(float(v))
    return {k: agg(v) for k, v in groups.items()}


def _outcome(row: dict[str, Any]) -> str:
    """Return the outcome of one point: a key of :data:`OUTCOMES`."""
    if row.get("criterion") == START_UNREACHABLE:
        return UNREACHABLE_LABEL
    if row["status"] in ("completed", "interrupted"):
        return str(row["status"])
    return "failed"


def _mark_points(ax: Any, rows: Rows, xa: _Axis, ya: _Axis) -> None:
    """Mark every sampled place with the marker of its worst outcome (:data:`OUTCOMES`)."""
    worst: dict[tuple[Any, Any], str] = {}
    order = list(OUTCOMES)
    for r in rows:
        place, outcome = (r[xa.key], r[ya.key]), _outcome(r)
        if place not in worst or order.index(outcome) < order.index(worst[place]):
            worst[place] = outcome
    for outcome, (marker, face, size) in OUTCOMES.items():
        places = sorted((p for p, o in worst.items() if o == outcome), key=str)
        if places:
            ax.plot([xa.pos(x) for x, _ in places], [ya.pos(y) for _, y in places], marker,
                    ls="none", mfc=face, mec="black", color="black", ms=size, mew=1.0,
                    label=outcome, gid=f"points:{outcome}", zorder=4)


def _span(ax: Any, xa: _Axis, ya: _Axis) -> None:
    """Limit the axes to the sampled values, with a margin of :data:`MARGIN` of their span."""
    for axis, which in ((xa, "x"), (ya, "y")):
        p = [axis.pos(v) for v in axis.levels]
        lo, hi = min(p), max(p)
        pad = (MARGIN * (hi - lo) if hi > lo
               else 0.5 if not axis.numeric or lo == 0 else MARGIN * abs(lo))
        if not axis.numeric:
            pad = max(pad, CATEGORY_MARGIN)
        getattr(ax, f"set_{which}lim")(lo - pad, hi + pad)


def _draw_map(fig: Figure, ax: Any, rows: Rows, kx: str, ky: str,
              values: dict[tuple[Any, Any], float], label: str, labels: Labels, *,
              never_inside: bool = False, **style: Any) -> None:
    """Draw ``values`` over (kx, ky), and mark every sampled place by its outcome.

    A full grid of at least :data:`MIN_CELL_LEVELS` values along each key is drawn as
    cells, one per place; a smaller grid, or places that fill no grid, as coloured
    squares at the places, so that a few samples never paint one solid block. The axes
    span the sampled values (:func:`_span`), and each place has the marker of its worst
    outcome (:func:`_mark_points`). With ``never_inside``, the places of points that ran
    but never got inside every range are circled.
    """
    xa = _Axis(kx, [r[kx] for r in rows], labels.get(kx))
    ya = _Axis(ky, [r[ky] for r in rows], labels.get(ky))
    full = len({(r[kx], r[ky]) for r in rows}) == len(xa.levels) * len(ya.levels)
    if full and min(len(xa.levels), len(ya.levels)) >= MIN_CELL_LEVELS:
        grid = np.full((len(ya.levels), len(xa.levels)), np.nan)
        for (x, y), v in values.items():
            grid[ya.levels.index(y), xa.levels.index(x)] = v
        art = ax.pcolormesh(xa.edges(), ya.edges(), np.ma.masked_invalid(grid), **style)
    else:
        pts = list(values.items())
        art = ax.scatter([xa.pos(x) for (x, _), _ in pts], [ya.pos(y) for (_, y), _ in pts],
                         c=[v for _, v in pts], s=400 if len(pts) <= 36 else 60, marker="s",
                         **style)
    fig.colorbar(art, ax=ax, label=label)
    xa.label(ax, "x")
    ya.label(ax, "y")
    _mark_points(ax, rows, xa, ya)
    if never_inside:
        ran = [r for r in rows if r["status"] != "interrupted"
               and r.get("criterion") != START_UNREACHABLE]
        inside = {(r[kx], r[ky]) for r in ran if _finite(r.get("recovered_at_s"))}
        never = sorted({(r[kx], r[ky]) for r in ran} - inside, key=str)
        if never:
            ax.plot([xa.pos(x) for x, _ in never], [ya.pos(y) for _, y in never], "o",
                    mfc="none", color="black", ms=13, mew=1.2, label=NEVER_INSIDE_LABEL,
                    zorder=4)
    _span(ax, xa, ya)


def _legend_below(fig: Figure) -> None:
    """One legend of the figure's markers, below its axes (never over a map's cells)."""
    handles: dict[str, Any] = {}
    for ax in fig.axes:
        for handle, label in zip(*ax.get_legend_handles_labels(), strict=True):
            handles.setdefault(label, handle)
    if handles:
        fig.legend(list(handles.values()), list(handles), loc="outside lower center",
                   ncols=len(handles), fontsize=8, frameon=False)


def _draw_curve(ax: Any, rows: Rows, key: str, metric: Callable[[dict[str, Any]], float],
                agg: Callable[[list[float]], float], label: str, labels: Labels,
                axis: _Axis | None = None) -> None:
    axis = axis or _Axis(key, [r[key] for r in rows], labels.get(key))
    groups: dict[Any, list[float]] = defaultdict(list)
    for r in rows:
        v = metric(r)
        if _finite(v):
            groups[r[key]].append(float(v))
    levels = [v for v in axis.levels if v in groups]
    ax.plot([axis.pos(v) for v in levels], [agg(groups[v]) for v in levels], "o-")
    axis.label(ax, "x")
    ax.set_ylabel(label)
    ax.grid(True, alpha=0.3)


def _mean(v: list[float]) -> float:
    return float(np.mean(v))


def _completion(r: dict[str, Any]) -> float:
    return float(r["path_completed_pct"]) if r["status"] != "interrupted" else math.nan


def completion_figure(rows: Rows, swept: Sequence[str], labels: Labels | None = None
                      ) -> Figure:
    """Path completed [%] over the first two swept keys (or along the only one)."""
    labels = labels or {}
    fig = _figure(figsize=(7.5, 5.5), layout="constrained")
    ax = fig.subplots()
    if len(swept) >= 2:
        _draw_map(fig, ax, rows, swept[0], swept[1],
                  _cells(rows, swept[0], swept[1], _completion, _mean),
                  "path completed [%] (mean)", labels, cmap="RdYlGn", vmin=0.0, vmax=100.0)
    else:
        _draw_curve(ax, rows, swept[0], _completion, _mean, "path completed [%] (mean)",
                    labels)
        ax.set_ylim(-5, 105)
    ax.set_title("Completion")
    _legend_below(fig)
    return fig


def _field(name: str, scale: float = 1.0) -> Callable[[dict[str, Any]], float]:
    """Return the metric reading a number of the record (NaN when missing), scaled."""
    def metric(r: dict[str, Any]) -> float:
        v: Any = r.get(name)
        return float(v) * scale if _finite(v) else math.nan
    return metric


_ratio = _field("worst_limit_ratio_after_recovery")
_margin_deg = _field("joint_margin_min_after_recovery_rad", 180.0 / math.pi)
_recovered_s = _field("recovered_at_s")


def limits_figure(rows: Rows, swept: Sequence[str], labels: Labels | None = None) -> Figure:
    """Draw the realised limits after the start-up recovery over the first two keys.

    Three maps (curves along a single key): the worst realised range or speed ratio, the
    smallest joint margin [deg] and the time until every variable is inside its range
    [s] (see :mod:`.recovery`). Points that never get inside are marked with a circle.
    """
    labels = labels or {}
    fig = _figure(figsize=(18, 5.4), layout="constrained")
    ax_r, ax_m, ax_t = fig.subplots(1, 3)
    r_text = "worst realised ratio after the recovery (max)"
    m_text = "smallest joint margin after the recovery [deg] (min)"
    t_text = "time to get inside every range [s] (max)"
    if len(swept) >= 2:
        kx, ky = swept[0], swept[1]
        ratios = _cells(rows, kx, ky, _ratio, max)
        top = max([*ratios.values(), 1.01])
        _draw_map(fig, ax_r, rows, kx, ky, ratios, r_text, labels, never_inside=True,
                  cmap="RdYlGn_r", norm=TwoSlopeNorm(1.0, vmin=0.0, vmax=top))
        _draw_map(fig, ax_m, rows, kx, ky, _cells(rows, kx, ky, _margin_deg, min), m_text,
                  labels, never_inside=True, cmap="viridis")
        _draw_map(fig, ax_t, rows, kx, ky, _cells(rows, kx, ky, _recovered_s, max), t_text,
                  labels, never_inside=True, cmap="YlOrRd", vmin=0.0)
    else:
        _draw_curve(ax_r, rows, swept[0], _ratio, max, r_text, labels)
        ax_r.axhline(1.0, color="red", lw=0.8)
        _draw_curve(ax_m, rows, swept[0], _margin_deg, min, m_text, labels)
        ax_m.axhline(0.0, color="red", lw=0.8)
        _draw_curve(ax_t, rows, swept[0], _recovered_s, max, t_text, labels)
    ax_r.set_title("Worst range or speed ratio after the recovery\n(above 1: outside a limit)")
    ax_m.set_title("Smallest joint margin after the recovery")
    ax_t.set_title("Start-up recovery: time until every variable\nis inside its range")
    _legend_below(fig)
    return fig


def _binned(axis_values: Sequence[Any]) -> Callable[[Any], Any]:
    """Return the level a value is drawn at: itself, or its bin's centre."""
    levels = sorted(set(axis_values), key=str)
    if not _is_numeric(list(levels)) or len(levels) <= MAX_LEVELS:
        return lambda v: v
    edges = np.histogram_bin_edges(np.asarray(levels, dtype=float), bins=10)
    centres = (edges[1:] + edges[:-1]) / 2

    def level(v: Any) -> Any:
        i = int(np.clip(np.searchsorted(edges, float(v), side="right") - 1, 0, len(centres) - 1))
        return float(centres[i])
    return level


def solver_figure(rows: Rows, swept: Sequence[str], labels: Labels | None = None) -> Figure:
    """Share of points completed against one swept key, one line per solver.

    The key is the first swept key that is not the solver's name; with the solver the
    only one, a bar per solver.
    """
    labels = labels or {}
    fig = _figure(figsize=(7.5, 4.8), layout="constrained")
    ax = fig.subplots()
    ran = [r for r in rows if r["status"] != "interrupted"]
    solvers = list(dict.fromkeys(str(r.get("solver") or r.get(SOLVER_KEY)) for r in ran))
    key = next((k for k in swept if k != SOLVER_KEY), None)
    if key is None:
        share = [np.mean([r["status"] == "completed" for r in ran
                          if str(r.get("solver") or r.get(SOLVER_KEY)) == s]) for s in solvers]
        ax.bar(solvers, share)
        ax.set_xlabel("solver")
    else:
        level = _binned([r[key] for r in ran])
        axis = _Axis(key, [level(r[key]) for r in ran], labels.get(key))
        for s in solvers:
            mine = [{**r, key: level(r[key]), "ok": float(r["status"] == "completed")}
                    for r in ran if str(r.get("solver") or r.get(SOLVER_KEY)) == s]
            if mine:
                _draw_curve(ax, mine, key, lambda r: r["ok"], _mean, "share completed",
                            labels, axis)
                ax.lines[-1].set_label(s)
        ax.legend(title="solver", fontsize=8)
    ax.set_ylim(-0.05, 1.05)
    ax.set_ylabel("share of points completed")
    ax.set_title("Success by solver" if key is None
                 else f"Success by solver against {labels.get(key) or key}")
    return fig
