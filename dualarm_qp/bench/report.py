"""Bench report: rows with the objective gap, then a table, CSV, JSON and a plot.

The objective gap of a solver on a configuration compares its objective (Eq. 37) with
the smallest objective any benched solver reached, step by step over the canonical
steps (see :mod:`.runner`), on the steps both solved within tolerance.
"""

from __future__ import annotations

import csv
import io
import math
import textwrap
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .._io import jsonable, write_text
from .._io import write_json as _write_json_file
from .runner import STATUSES, job_failure
from .table import render_table

#: Columns of ``bench.csv``, in order.
COLUMNS: tuple[str, ...] = (
    "config", "experiment", "solver", "completed", "success_rate", "steps", "steps_run",
    *(f"status_{s}" for s in STATUSES), "status_not_run",
    "step_time_median_s", "step_time_p99_s",
    "kinematics_time_median_s", "kinematics_time_p99_s",
    "assembly_time_median_s", "assembly_time_p99_s",
    "solve_time_median_s", "solve_time_p99_s",
    "verify_time_median_s", "verify_time_p99_s",
    "bound_violation_max", "eq_residual_max",
    "closure_pos_err_max_m", "closure_rot_err_max_rad",
    "margin_qf_min_rad", "margin_ql_min_rad", "margin_grasp_min_m",
    "objective_gap_max", "objective_gap_median", "objective_gap_rel_max",
    "objective_gap_steps",
    "replay_success_rate", "replay_solve_time_median_s", "bare_solve_time_median_s",
    "solve_over_bare", "timed_samples", "wall_time_s", "key", "message", "error",
    "not_applicable",
)


def objective_gaps(records: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """Return copies of ``records`` with ``objective_gap_*`` filled in, per configuration.

    ``objective_gap_max`` and ``objective_gap_median`` are ``objective - best`` over the
    canonical steps where this solver and at least one solver were within tolerance
    (``best`` is the smallest such objective); ``objective_gap_rel_max`` divides each
    step's gap by ``max(1, |best|)``; ``objective_gap_steps`` counts the steps. A failed
    job (:func:`~.runner.job_failure`) gets its reason in ``error``.
    """
    by_cfg: dict[str, list[dict[str, Any]]] = {}
    for rec in records:
        by_cfg.setdefault(str(rec.get("config")), []).append(rec)
    best: dict[str, np.ndarray] = {}
    for cfg, recs in by_cfg.items():
        objs = [o for o in (_objectives(r) for r in recs) if o is not None]
        if objs and len({o.size for o in objs}) == 1:
            with np.errstate(all="ignore"):
                stack = np.vstack(objs)
                best[cfg] = np.where(np.isnan(stack).all(axis=0), np.nan,
                                     np.nanmin(np.where(np.isnan(stack), np.inf, stack), axis=0))
    out = []
    for rec in records:
        row = {k: v for k, v in rec.items() if k != "replay_objective"}
        obj = _objectives(rec)
        b = best.get(str(rec.get("config")))
        gap_max = gap_med = gap_rel = float("nan")
        n = 0
        if obj is not None and b is not None and obj.size == b.size:
            both = ~np.isnan(obj) & ~np.isnan(b)
            n = int(both.sum())
            if n:
                gap = obj[both] - b[both]
                gap_max, gap_med = float(gap.max()), float(np.median(gap))
                gap_rel = float((gap / np.maximum(1.0, np.abs(b[both]))).max())
        row.update(objective_gap_max=gap_max, objective_gap_median=gap_med,
                   objective_gap_rel_max=gap_rel,
                   objective_gap_steps=n)
        reason = job_failure(rec)
        if reason is not None:
            row["error"] = reason
        out.append(row)
    return out


def _objectives(rec: dict[str, Any]) -> np.ndarray | None:
    vals = rec.get("replay_objective")
    if not isinstance(vals, list):
        return None
    return np.array([np.nan if v is None else float(v) for v in vals], dtype=float)


def _fmt(value: Any, kind: str) -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "-"
    if kind == "us":
        return f"{float(value) * 1e6:.0f}"
    if kind == "rate":
        return f"{float(value):.3f}"
    if kind == "ratio":
        return f"{float(value):.2f}"
    if kind == "sci":
        return f"{float(value):.1e}"
    return str(value)


#: (header, column, format) of the printed table.
TABLE: tuple[tuple[str, str, str], ...] = (
    ("config", "experiment", "str"),
    ("solver", "solver", "str"),
    ("success", "success_rate", "rate"),
    ("step med us", "step_time_median_s", "us"),
    ("step p99 us", "step_time_p99_s", "us"),
    ("kin med", "kinematics_time_median_s", "us"),
    ("asm med", "assembly_time_median_s", "us"),
    ("solve med", "solve_time_median_s", "us"),
    ("verify med", "verify_time_median_s", "us"),
    ("solve/bare", "solve_over_bare", "ratio"),
    ("bound viol", "bound_violation_max", "sci"),
    ("eq resid", "eq_residual_max", "sci"),
    ("closure m", "closure_pos_err_max_m", "sci"),
    ("margin rad", "margin_qf_min_rad", "sci"),
    ("obj gap rel", "objective_gap_rel_max", "sci"),
)


#: What each column of the printed table means (header, meaning).
TABLE_LEGEND: tuple[tuple[str, str], ...] = (
    ("success", "usable steps / planned steps"),
    ("step med us, step p99 us", "whole controller step, median and 99th percentile [us]"),
    ("kin med, asm med, solve med, verify med",
     "its parts, medians [us]: both arms' kinematics, problem assembly, solve (with the "
     "infeasible-step policy), verification"),
    ("solve/bare", "qp:* solvers only: our whole solve over the backend's own solve time "
                   "on the same steps (the cost around the backend; 1 = none)"),
    ("bound viol", "worst bound violation of a step [rad/s, m/s] (0: the limits held)"),
    ("eq resid", "worst residual of the step's equality (the task)"),
    ("closure m", "worst grasp closure error [m]"),
    ("margin rad", "smallest distance of a follower joint to the end of its range [rad]; "
                   "negative: outside (the paper's start, Table 2, is)"),
    ("obj gap rel", "worst objective gap to the best solver on the same steps, relative"),
)


def table_legend() -> str:
    """Return the legend of :func:`format_table`'s columns, an entry a column (text)."""
    lines = ["columns:"]
    for header, text in TABLE_LEGEND:
        lines += textwrap.wrap(f"{header}: {text}", 96, initial_indent="  ",
                               subsequent_indent="      ")
    return "\n".join(lines)


def jobs_line(computed: int, done: int, planned: int) -> str:
    """Say how many jobs this bench computed, reused from the store, and did not run.

    Parameters
    ----------
    computed : int
        Jobs computed by this call.
    done : int
        Jobs with a result (computed, or read back from the store: an earlier bench in
        the same folder, or one running beside it).
    planned : int
        Jobs asked for.
    """
    parts = [f"{computed} of {planned} job{'s' if planned != 1 else ''} computed now"]
    if done > computed:
        parts.append(f"{done - computed} reused from the store (resumed)")
    if planned > done:
        parts.append(f"{planned - done} not run")
    return ", ".join(parts)


def format_table(rows: Sequence[dict[str, Any]], *, markdown: bool = False) -> str:
    """Format the rows as a text table (or a Markdown table); times in microseconds.

    A job that raised an error shows ``ERROR`` in place of its numbers; every failed
    job (:func:`~.runner.job_failure`) is listed with its reason under the table. A job
    whose solver cannot take the file's limits shows ``n/a`` and is listed as not run.
    """
    cells = [[h for h, _, _ in TABLE]]
    failed = []
    skipped = []
    for r in rows:
        if r.get("not_applicable"):
            skipped.append(f"{r.get('experiment')} / {r.get('solver')}: {r['not_applicable']}")
            cells.append([str(r.get("experiment")), str(r.get("solver")), "n/a"]
                         + [""] * (len(TABLE) - 3))
            continue
        reason = job_failure(r)
        if reason is not None:
            failed.append(f"{r.get('experiment')} / {r.get('solver')}: {reason}")
        if r.get("error") and not r.get("steps_run"):
            cells.append([str(r.get("experiment")), str(r.get("solver")), "ERROR"]
                         + [""] * (len(TABLE) - 3))
            continue
        cells.append([_fmt(r.get(col), kind) for _, col, kind in TABLE])
    text = render_table(cells, markdown=markdown, left_columns=2)
    sep = "\n\n" if markdown else "\n"
    if skipped:
        text += sep + "\n".join(["Not applicable (not run):",
                                 *(f"- {f}" if markdown else f"  {f}" for f in skipped)])
    if failed:
        text += sep + "\n".join(["Failed jobs:", *(f"- {f}" if markdown else f"  {f}"
                                                      for f in failed)])
    return text


def write_csv(path: Path, rows: Sequence[dict[str, Any]]) -> None:
    """One row per (configuration, solver); SI units; empty cells for missing values."""
    buf = io.StringIO()
    w = csv.writer(buf)
    w.writerow(COLUMNS)
    for r in rows:
        out = []
        for col in COLUMNS:
            v = jsonable(r.get(col))
            out.append("" if v is None else repr(v) if isinstance(v, float) else str(v))
        w.writerow(out)
    write_text(path, buf.getvalue())


def write_json(path: Path, rows: Sequence[dict[str, Any]], meta: dict[str, Any]) -> None:
    """``{"meta": ..., "rows": [...]}`` with non-finite numbers as null."""
    doc = {"meta": meta, "columns": list(COLUMNS),
           "rows": [{k: r.get(k) for k in COLUMNS} for r in rows]}
    _write_json_file(path, doc)


def plot(path: Path, rows: Sequence[dict[str, Any]]) -> None:
    """Write ``bench.png``: step time (log axis), success and accuracy per solver.

    See :func:`~.figure.bench_figure`.
    """
    from ..experiments.figures.canvas import save_png
    from .figure import bench_figure

    save_png(bench_figure(rows), path)


def write_report(out_dir: Path, records: Sequence[dict[str, Any]], meta: dict[str, Any],
                 *, plots: bool = True) -> list[dict[str, Any]]:
    """Write ``bench.json``, ``bench.csv`` and (optionally) ``bench.png``; return the rows."""
    rows = objective_gaps(records)
    write_json(out_dir / "bench.json", rows, meta)
    write_csv(out_dir / "bench.csv", rows)
    if plots:
        plot(out_dir / "bench.png", rows)
    return rows
