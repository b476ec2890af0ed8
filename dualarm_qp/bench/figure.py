"""``bench.png``: time, success and accuracy of each solver on each configuration.

One row of three panels per configuration, solvers down the rows:

- **time** [us], log axis: median step time (dot), its parts (kinematics, assembly,
  solve, verify; small markers) and the 99th percentile (bar end), so that medians of
  ~100 us and p99 outliers of milliseconds are both readable;
- **success**: share of the canonical steps solved within tolerance (bar), and the
  replayed share when measured (diamond);
- **accuracy**, log axis: largest bound violation, equality residual, closure error [m]
  and relative objective gap; an exact zero is drawn hollow at the axis floor.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from ..experiments.figures.canvas import new_figure

#: Step time parts: (label, column, marker).
TIME_PARTS = (("kinematics", "kinematics_time_median_s", "v"),
              ("assembly", "assembly_time_median_s", "^"),
              ("solve", "solve_time_median_s", "s"),
              ("verify", "verify_time_median_s", "x"))

#: Accuracy measures: (label, column, marker).
ACCURACY = (("bound violation", "bound_violation_max", "o"),
            ("equality residual", "eq_residual_max", "s"),
            ("closure error [m]", "closure_pos_err_max_m", "^"),
            ("objective gap (rel.)", "objective_gap_rel_max", "D"))

#: Where an exact zero sits on the accuracy axis.
ACCURACY_FLOOR = 1e-17


def _num(row: dict[str, Any], col: str) -> float:
    v = row.get(col)
    try:
        return float(v) if v is not None else float("nan")
    except (TypeError, ValueError, OverflowError):
        return float("nan")


def _time_panel(ax: Any, rs: Sequence[dict[str, Any]], y: np.ndarray) -> None:
    med = np.array([_num(r, "step_time_median_s") for r in rs]) * 1e6
    p99 = np.array([_num(r, "step_time_p99_s") for r in rs]) * 1e6
    ax.hlines(y, med, p99, color="0.6", lw=1.5, label="median to p99")
    ax.plot(p99, y, "|", color="k", ms=10, label="step p99")
    for k, (label, col, marker) in enumerate(TIME_PARTS):
        ax.plot([_num(r, col) * 1e6 for r in rs], y, marker, color=f"C{k + 1}", ms=5,
                ls="none", label=label)
    ax.plot(med, y, "o", color="C0", ms=7, label="step median")
    ax.set_xscale("log")


def _success_panel(ax: Any, rs: Sequence[dict[str, Any]], y: np.ndarray) -> None:
    rate = np.array([_num(r, "success_rate") for r in rs])
    ax.barh(y, np.nan_to_num(rate), color=np.where(rate >= 1.0, "C2", "C3"), height=0.6)
    replay = np.array([_num(r, "replay_success_rate") for r in rs])
    ax.plot(replay, y, "D", color="k", ms=4, ls="none", label="replayed")
    for yi, v in zip(y, rate, strict=True):
        if np.isfinite(v):
            ax.text(0.02, yi, f"{v:.3f}", va="center", fontsize=7, color="w")
    ax.set_xlim(0, 1.05)


def _accuracy_panel(ax: Any, rs: Sequence[dict[str, Any]], y: np.ndarray) -> None:
    for k, (label, col, marker) in enumerate(ACCURACY):
        v = np.array([abs(_num(r, col)) for r in rs])
        zero = v == 0.0
        shown = np.where(zero, ACCURACY_FLOOR, v)
        off = (k - 1.5) * 0.12  # side by side in a row
        ax.plot(shown[~zero], y[~zero] + off, marker, color=f"C{k}", ms=5, ls="none",
                label=label)
        ax.plot(shown[zero], y[zero] + off, marker, mfc="none", color=f"C{k}", ms=5,
                ls="none")
    ax.set_xscale("log")


def bench_figure(rows: Sequence[dict[str, Any]]) -> Figure:
    """Draw the bench rows (see the module docstring); failed jobs are left out.

    Returns
    -------
    Figure
        Per configuration, axes ``time`` (log x), ``success`` and ``accuracy`` (log x),
        in that order.
    """
    good = [r for r in rows if not r.get("error") or r.get("steps_run")]
    configs = list(dict.fromkeys(str(r.get("experiment")) for r in good)) or ["(none)"]
    n_rows = max((sum(1 for r in good if str(r.get("experiment")) == c) for c in configs),
                 default=1)
    height = len(configs) * (0.3 * max(n_rows, 1) + 0.9) + 1.0
    fig = new_figure(figsize=(12, height))
    axes = fig.subplots(len(configs), 3, squeeze=False,
                        gridspec_kw={"width_ratios": (3, 1.2, 2)})
    for (ax_t, ax_s, ax_a), cfg in zip(axes, configs, strict=True):
        rs = [r for r in good if str(r.get("experiment")) == cfg]
        y = np.arange(len(rs), dtype=float)
        if rs:
            _time_panel(ax_t, rs, y)
            _success_panel(ax_s, rs, y)
            _accuracy_panel(ax_a, rs, y)
        ax_t.set_yticks(y, [str(r.get("solver")) for r in rs], fontsize=8)
        for ax in (ax_s, ax_a):
            ax.set_yticks(y, [""] * len(rs))
        for ax in (ax_t, ax_s, ax_a):
            ax.set_ylim(len(rs) - 0.5, -0.5)
            ax.grid(axis="x", color="0.9", lw=0.6)
            ax.tick_params(axis="x", labelsize=7)
        ax_t.set_title(f"{cfg}: controller step time [us]", fontsize=9)
        ax_s.set_title("success rate", fontsize=9)
        ax_a.set_title("accuracy (hollow: exactly 0)", fontsize=9)
    handles, labels = [], []
    for ax in axes[0]:
        h, lab = ax.get_legend_handles_labels()
        handles += h
        labels += lab
    fig.legend(handles, labels, fontsize=7, loc="lower center", ncol=6, frameon=False)
    fig.tight_layout(rect=(0, 0.75 / height, 1, 1))
    return fig
