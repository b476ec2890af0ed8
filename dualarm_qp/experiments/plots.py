"""PNG plots of a run: joints against their limits, the grasp, the closure error.

The figures are drawn with matplotlib's object interface (:class:`~matplotlib.figure.
Figure` on an Agg canvas), never through :mod:`matplotlib.pyplot`: importing or using
this module leaves the user's backend choice and pyplot's figures alone.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from ..control.trace import Trace
from ..kinematics.arm import SerialArm
from ..task.surfaces import GraspSurface
from .outputs import atomic_write_with


def _figure(**kwargs: Any) -> Figure:
    """Return a figure on its own Agg canvas (no pyplot, no global state)."""
    fig = Figure(**kwargs)
    FigureCanvasAgg(fig)
    return fig


def _save(fig: Figure, path: Path) -> None:
    atomic_write_with(path, lambda tmp: fig.savefig(tmp, dpi=110, format="png"))


def plot_joints(path: Path, trace: Trace, leader: SerialArm, follower: SerialArm,
                title: str = "") -> None:
    """Both arms' joints [deg] against time with their ranges shaded out."""
    n = max(leader.n, follower.n)
    fig = _figure(figsize=(2.6 * n, 5.2))
    axes = fig.subplots(2, n, sharex=True, squeeze=False)
    for row, (arm, q, label) in enumerate(((leader, trace.q_l, "leader"),
                                           (follower, trace.q_f, "follower"))):
        for j in range(n):
            ax = axes[row][j]
            if j >= arm.n:
                ax.set_visible(False)
                continue
            ax.plot(trace.t, np.rad2deg(q[:, j]), color="C0" if row else "C2", lw=1.2)
            for lim in (arm.q_min[j], arm.q_max[j]):
                if np.isfinite(lim):
                    ax.axhline(np.rad2deg(lim), color="C3", ls="--", lw=0.9)
            ax.set_title(f"{label} q{j + 1}", fontsize=9)
            ax.tick_params(labelsize=7)
            if row == 1:
                ax.set_xlabel("t [s]", fontsize=8)
        axes[row][0].set_ylabel("[deg]", fontsize=8)
    fig.suptitle(title or "joints against their ranges (dashed)", fontsize=10)
    fig.tight_layout()
    _save(fig, path)


def plot_grasp(path: Path, trace: Trace, surface: GraspSurface, title: str = "") -> None:
    """Grasp coordinate [mm] and sliding speed [mm/s] against time."""
    fig = _figure(figsize=(7, 5))
    ax1, ax2 = fig.subplots(2, 1, sharex=True)
    ax1.plot(trace.t, trace.grasp * 1e3, color="C0")
    for lim in (surface.sigma_min, surface.sigma_max):
        ax1.axhline(lim * 1e3, color="C3", ls="--", lw=0.9)
    ax1.set_ylabel("grasp [mm]")
    ax2.plot(trace.t, trace.m * 1e3, color="C1")
    ax2.set_ylabel("m [mm/s]")
    ax2.set_xlabel("t [s]")
    fig.suptitle(title or "follower grasp position along the bar", fontsize=10)
    fig.tight_layout()
    _save(fig, path)


def plot_closure(path: Path, trace: Trace, title: str = "", *,
                 tolerance: tuple[float, float] | None = None) -> None:
    """Grasp closure error (Eq. 15) against time, log scale.

    ``tolerance`` is the run's ``(position [m], rotation [rad])`` closure tolerance,
    beyond which it fails; drawn when given. Where a position-level correction ran (the
    paper's methods), the error of the integrated state before it is drawn too.
    """
    fig = _figure(figsize=(7, 3.6))
    ax = fig.subplots()
    floor = 1e-16
    marker = "o" if len(trace) < 20 else None
    ax.semilogy(trace.t, np.maximum(trace.closure_pos_err, floor), marker=marker,
                label="position [m]")
    ax.semilogy(trace.t, np.maximum(trace.closure_rot_err, floor), marker=marker,
                label="rotation [rad]")
    if np.nanmax(trace.correction_f, initial=0.0) > 0.0:
        ax.semilogy(trace.t, np.maximum(trace.closure_pos_err_pre, floor), color="C0",
                    ls=":", lw=0.9, label="position before the position-level correction")
    if tolerance is not None:
        ax.axhline(tolerance[0], color="C0", ls="--", lw=0.9,
                   label=f"tolerance {tolerance[0]:g} m (the run fails above)")
        ax.axhline(tolerance[1], color="C1", ls="--", lw=0.9,
                   label=f"tolerance {tolerance[1]:g} rad")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("closure error")
    ax.legend(fontsize=7)
    ax.set_title(title or "grasp closure error", fontsize=10)
    fig.tight_layout()
    _save(fig, path)


def plot_compare(path: Path, traces: Sequence[tuple[str, Trace]], column: str,
                 *, joint: int | None = None, limits: tuple[float, float] | None = None,
                 ylabel: str = "", title: str = "", scale: float = 1.0,
                 note: str = "") -> None:
    """One quantity of several runs on one axis (e.g. the paper's Figs. 5 and 6).

    The axis spans the data; a range limit (dashed) far outside the data is named in
    the legend instead of squeezing the curves.
    """
    fig = _figure(figsize=(7, 4))
    ax = fig.subplots()
    lo, hi = np.inf, -np.inf
    for label, tr in traces:
        y = getattr(tr, column)
        if joint is not None:
            y = y[:, joint]
        ax.plot(tr.t, y * scale, label=label)
        if y.size:
            lo, hi = min(lo, float(np.nanmin(y))), max(hi, float(np.nanmax(y)))
    lo, hi = lo * scale, hi * scale
    if scale < 0:
        lo, hi = hi, lo
    span = max(hi - lo, 1e-9)
    pad = 0.08 * span
    view = (lo - pad, hi + pad)
    if limits is not None:
        shown: list[float] = []
        hidden: list[float] = []
        for lim in limits:
            v = lim * scale
            near = lo - 0.5 * span <= v <= hi + 0.5 * span
            (shown if near else hidden).append(v)
        for v in shown:
            view = (min(view[0], v - pad), max(view[1], v + pad))
            ax.axhline(v, color="C3", ls="--", lw=0.9)
        if shown:
            ax.plot([], [], color="C3", ls="--", lw=0.9,
                    label="range limit " + ", ".join(f"{v:.4g}" for v in shown))
        if hidden:
            ax.plot([], [], color="none",
                    label="off the axis: limit " + ", ".join(f"{v:.4g}" for v in hidden))
    ax.set_ylim(*view)
    ax.set_xlabel("t [s]")
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    ax.legend(fontsize=8)
    fig.tight_layout(rect=(0, 0.05 if note else 0, 1, 1))
    if note:
        fig.text(0.01, 0.015, note, fontsize=7, color="0.3")
    _save(fig, path)
