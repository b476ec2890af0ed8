"""The figures of one run, drawn from its ``trajectory.csv`` and the limits it had.

One function per figure returns the :class:`~matplotlib.figure.Figure` (so that tests
can read what was drawn); :func:`write_run_figures` writes them all as PNG files:

- ``joints.png``: every joint against its range, shaded where outside;
- ``rates.png``: every joint rate, commanded and realised (finite differences
  of the recorded joints), against its speed limit, shaded where the realised rate is
  over it; with acceleration (jerk) limits, the realised accelerations (jerks) against
  theirs (all in lanes, one lane per joint in one axis each: :mod:`.lanes`);
- ``grasp.png``: the grasp coordinate against its range, and the sliding speed
  against its limit;
- ``tracking.png``: the leader's tracking error, the smallest singular value of each
  arm's Jacobian and the task scale;
- ``closure.png``: the grasp closure error (Eq. 15);
- ``clearance.png``, for a run with a collision scene only: the smallest distance of
  each group of pairs against the safety and influence distances (:mod:`.clearance`).

Angles and lengths are shown in the experiment file's units (deg or rad, mm or m:
:class:`~.rundata.DisplayUnits`). The sliding speed's axis is symmetric-logarithmic,
linear inside the limit, with round ticks (:func:`~.canvas.speed_axis`): the paper's
unbounded first step, thousands of times the limit, stays on the axis without
flattening the rest. Each axis has at most a few round ticks, and a column of axes
that share the time ticks it on the bottom one only (:func:`~.canvas.few_ticks`): the
ticks are much of the cost of drawing a figure.

:func:`write_figures` draws and writes any of the figures, by file name, from the
limits alone (no experiment): what a drawing process (:mod:`.process`) is sent.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from matplotlib.figure import Figure

from .canvas import (
    TICKS,
    few_ticks,
    finite_max_abs,
    fixed_margins,
    limit_lines,
    log_axis,
    log_y,
    new_figure,
    note_bottom,
    outside_mask,
    outside_spans,
    panel_title,
    save_png,
    shade_spans,
    shared_time,
    speed_axis,
    tick_text,
)
from .clearance import CLEARANCE_FIGURE, clearance_figure, has_clearance
from .lanes import joints_figure, rates_figure
from .ready import builder, take, ticks_ahead
from .rundata import PlotLimits, RunData, realised_rate, run_title

if TYPE_CHECKING:
    from ..setup import Experiment

#: The PNG files of every run, in the order they are written (a run with a collision
#: scene adds :data:`~.clearance.CLEARANCE_FIGURE` after them).
RUN_FIGURES = ("joints.png", "rates.png", "grasp.png", "tracking.png", "closure.png")

#: How far the error axes go below the smallest tolerance [powers of ten]: an error a
#: million times smaller than its tolerance is drawn on the bottom edge.
LOG_DECADES = 6


def _column(height: float, rows: int) -> tuple[Figure, Any]:
    """Return a figure ``height`` [in] high of ``rows`` axes sharing their time axis."""
    fig = new_figure(figsize=(8, height))
    axes = list(fig.subplots(rows, 1, sharex=True, squeeze=False)[:, 0])
    for ax in axes:
        few_ticks(ax)
    shared_time(axes)
    ticks_ahead(*axes, count=TICKS + 1)
    return fig, (tuple(axes) if rows > 1 else axes[0])


builder("grasp")(lambda: _column(6.0, 2))
builder("tracking")(lambda: _column(7.5, 3))
builder("closure")(lambda: _column(3.8, 1))


def grasp_figure(data: RunData, limits: PlotLimits, title: str = "") -> Figure:
    """Grasp coordinate against its range, sliding speed against its limit.

    Lengths in the file's unit (mm or m).

    The commanded sliding speed is the ``m`` column (without the last row's, never
    applied), the realised one the finite difference of the recorded grasp. A
    ``grasp_leader`` column (a leader whose grasp also slides) is drawn beside the
    follower's, with ``m_leader`` and the leader's grasp range when known.
    """
    fig, (ax1, ax2) = take("grasp")
    t = data.t
    per_m, unit = limits.units.per_m, limits.units.length
    lo, hi = limits.grasp_range
    grasp = data.col("grasp")
    ax1.plot(t, grasp * per_m, color="C0", label="follower grasp")
    limit_lines(ax1, (lo, hi), "grasp", scale=per_m, label="grasp range")
    shade_spans(ax1, outside_spans(t, outside_mask(grasp, lo, hi)), "grasp",
                label="outside the range")
    if data.has("grasp_leader"):
        g_l = data.col("grasp_leader")
        ax1.plot(t, g_l * per_m, color="C2", label="leader grasp")
        if limits.leader_grasp_range is not None:
            lo_l, hi_l = limits.leader_grasp_range
            limit_lines(ax1, (lo_l, hi_l), "grasp_leader", scale=per_m, colour="C2",
                        label="leader grasp range")
            shade_spans(ax1, outside_spans(t, outside_mask(g_l, lo_l, hi_l)), "grasp_leader",
                        colour="C2")
    ax1.set_ylabel(f"grasp [{unit}]")
    ax1.legend(fontsize=7)

    speed = limits.grasp_speed_max
    real = realised_rate(t, grasp)
    m = data.col("m")[:-1]
    ax2.plot(t[:-1], m * per_m, color="C0", lw=1.1, label="commanded m")
    ax2.plot(t, real * per_m, color="C1", lw=0.9, ls=":", label="realised")
    peak = finite_max_abs(m, real) * per_m
    if data.has("grasp_leader"):
        real_l = realised_rate(t, data.col("grasp_leader"))
        ax2.plot(t, real_l * per_m, color="C2", lw=0.9, ls=":", label="leader grasp, realised")
        peak = max(peak, finite_max_abs(real_l) * per_m)
        if data.has("m_leader"):
            ax2.plot(t[:-1], data.col("m_leader")[:-1] * per_m, color="C2", lw=1.1,
                     label="leader grasp, commanded")
            peak = max(peak, finite_max_abs(data.col("m_leader")[:-1]) * per_m)
    if np.isfinite(speed):
        limit_lines(ax2, (-speed, speed), "grasp_speed", scale=per_m,
                    label=f"speed limit {tick_text(speed * per_m)} {unit}/s")
        shade_spans(ax2, outside_spans(t, outside_mask(real, -speed, speed)), "grasp_speed",
                    label="realised over the limit")
    else:
        ax2.plot([], [], color="none", label="no sliding speed limit in this run")
    speed_axis(ax2, speed * per_m, peak)
    ax2.set_ylabel(f"sliding speed [{unit}/s]")
    ax2.set_xlabel("t [s]")
    ax2.legend(fontsize=7, title=f"largest |speed| {peak:.4g} {unit}/s", title_fontsize=7)
    fig.suptitle((title + ": " if title else "") + "grasp position along the bar",
                 fontsize=10)
    fixed_margins(fig, hspace=0.1)
    return fig


def tracking_figure(data: RunData, limits: PlotLimits, title: str = "") -> Figure:
    """Leader tracking error, smallest singular values and task scale against time."""
    fig, (ax1, ax2, ax3) = take("tracking")
    t = data.t
    errors = (data.col("leader_pos_err"), data.col("leader_rot_err"))
    log_y(ax1)
    floor = log_axis(ax1, limits.tracking, errors, decades=LOG_DECADES)
    ax1.plot(t, np.maximum(errors[0], floor), color="C0", label="position [m]")
    ax1.plot(t, np.maximum(errors[1], floor), color="C1", label="rotation [rad]")
    limit_lines(ax1, (limits.tracking[0],), "tracking_pos", colour="C0",
                label=f"tolerance {limits.tracking[0]:g} m")
    limit_lines(ax1, (limits.tracking[1],), "tracking_rot", colour="C1",
                label=f"tolerance {limits.tracking[1]:g} rad")
    note_bottom(ax1, floor, errors)
    ax1.set_ylabel("leader error to D(t)")
    ax1.legend(fontsize=7, ncol=2)

    s_min = limits.singular_value_min
    log_y(ax2)
    floor = log_axis(ax2, (s_min,), (data.col("sigma_min_l"), data.col("sigma_min_f")),
                     decades=2)
    for name, colour, label in (("sigma_min_l", "C2", "leader"),
                                ("sigma_min_f", "C0", "follower")):
        ax2.plot(t, np.maximum(data.col(name), floor), color=colour, label=label)
    if s_min > 0:
        limit_lines(ax2, (s_min,), "singular_value_min",
                    label=f"singularity threshold {s_min:g}")
        near = outside_mask(data.col("sigma_min_l"), s_min) | outside_mask(
            data.col("sigma_min_f"), s_min)
        shade_spans(ax2, outside_spans(t, near), "singular_value_min",
                    label="an arm below the threshold")
    note_bottom(ax2, floor, (data.col("sigma_min_l"), data.col("sigma_min_f")))
    ax2.set_ylabel("smallest singular\nvalue of J")
    ax2.legend(fontsize=7, ncol=2)

    # The last row's command is computed but never applied (the path is done): left out.
    scale = data.col("scale")[:-1]
    ax3.plot(t[:-1], scale, color="C0", label="task scale")
    if data.has("leader_scale"):
        ax3.plot(t[:-1], data.col("leader_scale")[:-1], color="C2", ls="--", lw=0.9,
                 label="leader task scale")
    shade_spans(ax3, outside_spans(t[:-1], outside_mask(scale, 1.0)), "scale",
                colour="0.5", label="scaled down (< 1)")
    ax3.set_ylim(-0.05, 1.1)
    ax3.set_ylabel("task scale")
    ax3.set_xlabel("t [s]")
    ax3.legend(fontsize=7, ncol=3)
    fig.suptitle((title + ": " if title else "")
                 + "leader tracking, conditioning, task scale", fontsize=10)
    fixed_margins(fig, hspace=0.1)
    return fig


def closure_figure(data: RunData, limits: PlotLimits, title: str = "") -> Figure:
    """Grasp closure error (Eq. 15) against time, log scale, with its tolerance.

    Where a position-level correction ran (the paper's methods), the error of the
    integrated state before it is drawn too.
    """
    fig, ax = take("closure")
    t = data.t
    marker = "o" if len(data) < 20 else None
    corrected = np.nanmax(data.col("correction_f"), initial=0.0) > 0.0
    errors = [data.col("closure_pos_err"), data.col("closure_rot_err")]
    drawn = [*errors, data.col("closure_pos_err_pre") if corrected else np.zeros(0)]
    log_y(ax)
    floor = log_axis(ax, limits.closure, drawn, decades=LOG_DECADES)
    ax.plot(t, np.maximum(errors[0], floor), marker=marker, color="C0", label="position [m]")
    ax.plot(t, np.maximum(errors[1], floor), marker=marker, color="C1",
            label="rotation [rad]")
    if corrected:
        ax.plot(t, np.maximum(data.col("closure_pos_err_pre"), floor), color="C0",
                ls=":", lw=0.9, label="position before the position-level correction")
    limit_lines(ax, (limits.closure[0],), "closure_pos", colour="C0",
                label=f"tolerance {limits.closure[0]:g} m (the run fails above)")
    limit_lines(ax, (limits.closure[1],), "closure_rot", colour="C1",
                label=f"tolerance {limits.closure[1]:g} rad")
    note_bottom(ax, floor, drawn)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("closure error")
    ax.legend(fontsize=7)
    panel_title(ax, (title + ": " if title else "") + "grasp closure error", fontsize=10)
    fixed_margins(fig, top=0.35)
    return fig


def run_figure_names(data: RunData, limits: PlotLimits) -> list[str]:
    """Return the PNG files of a run, in the order they are listed.

    :data:`RUN_FIGURES`, then ``clearance.png`` when the run had a collision scene; none
    for an empty run.
    """
    if not len(data):
        return []
    clearance = limits.clearance is not None and has_clearance(data)
    return [*RUN_FIGURES, *([CLEARANCE_FIGURE] if clearance else [])]


def write_figures(out: Path, limits: PlotLimits, title: str, names: list[str], *,
                  data: RunData | None = None) -> None:
    """Draw the figures ``names`` (of :func:`run_figure_names`) and write them into ``out``.

    Each file is written atomically. ``data`` is the trajectory (default: read
    ``out/trajectory.csv``).
    """
    if data is None:
        data = RunData.read(out / "trajectory.csv")
    draw = {"joints.png": joints_figure, "rates.png": rates_figure, "grasp.png": grasp_figure,
            "tracking.png": tracking_figure, "closure.png": closure_figure,
            CLEARANCE_FIGURE: clearance_figure}
    for name in names:
        save_png(draw[name](data, limits, title), out / name)


def write_run_figures(out: Path, exp: Experiment, *, data: RunData | None = None,
                      title: str | None = None) -> list[str]:
    """Write the PNG figures of a run (:data:`RUN_FIGURES`) into ``out``.

    A run whose task had a collision scene (its trace has the clearance columns) also
    gets ``clearance.png``, last.

    Parameters
    ----------
    out : Path
        The run folder.
    exp : Experiment
        The experiment the run was made with: the limits are read from it.
    data : RunData, optional
        The trajectory; default: read ``out/trajectory.csv``.
    title : str, optional
        Title prefix; default :func:`run_title`.

    Returns
    -------
    list of str
        The file names written, in :data:`RUN_FIGURES` order, then ``clearance.png``
        (none for an empty run).
    """
    if data is None:
        data = RunData.read(out / "trajectory.csv")
    limits = PlotLimits.from_experiment(exp)
    names = run_figure_names(data, limits)
    write_figures(out, limits, run_title(exp) if title is None else title, names, data=data)
    return names


__all__ = ["RUN_FIGURES", "closure_figure", "grasp_figure", "joints_figure",
           "rates_figure", "run_figure_names", "tracking_figure", "write_figures",
           "write_run_figures"]
