"""The sweep report: ``report.html`` with maps of where the task succeeds, and why not.

One self-contained HTML file (figures inlined as base64 PNG, no external file or
script) with

1. a **completion map**: the share of the path completed [%] over the first two swept
   keys (the mean over any other swept keys; points that cannot even start are
   crossed out);
2. **limit maps** of the motion after the start-up recovery (:mod:`.recovery`): the
   worst realised limit ratio (range or speed, leader, follower or grasp; above 1 is
   outside a limit), the smallest joint margin [deg] and the time until every variable
   is inside its range [s], over the same two keys (the worst over any other keys);
3. **success by solver**: the share of points that completed against one swept key
   (the first one that is not the solver), one line per solver;
4. the **ten worst points**: failed ones first (least path completed), then the highest
   limit ratios.

With one swept key the maps are curves over it. Figures are drawn with matplotlib's
object interface on an Agg canvas (never :mod:`matplotlib.pyplot`), see
:mod:`.maps`.
"""

from __future__ import annotations

import base64
import html
import io
import json
import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from .._io import atomic_write_with, write_text
from ..errors import InvalidInputError
from .maps import completion_figure, limits_figure, solver_figure
from .table import POINT_COLUMN, read_table

REPORT_FILE = "report.html"

#: Rows in the report's table of worst points.
WORST_ROWS = 10


#: The figures: file name (also written beside the report) and title.
FIGURES = (("map_completion.png", "Completion"),
           ("map_limits.png", "Realised limits and margins after the start-up recovery"),
           ("success_by_solver.png", "Success by solver"))


def _png(fig: Any) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100)
    return buf.getvalue()


def draw_figures(rows: Sequence[dict[str, Any]], swept: Sequence[str],
                 labels: Mapping[str, str] | None = None) -> dict[str, bytes]:
    """Draw the report's figures as PNG bytes, by file name (see :data:`FIGURES`).

    ``labels`` are the axis labels of the swept keys (default: the keys).
    """
    figures = (completion_figure(rows, swept, labels), limits_figure(rows, swept, labels),
               solver_figure(rows, swept, labels))
    return {name: _png(fig) for (name, _), fig in zip(FIGURES, figures, strict=True)}


def _swept(rows: Sequence[dict[str, Any]], meta: dict[str, Any], *,
           axes: bool = False) -> list[str]:
    """Return the swept keys that are table columns.

    With ``axes``, only those varied freely (not the paired ones): the maps' axes.
    """
    keys = meta.get("swept_keys", [])
    if axes:
        keys = meta.get("map_keys", keys)
    swept = [k for k in keys if rows and k in rows[0]]
    if not swept:
        raise InvalidInputError("the sweep's table has no row or no swept key column")
    return swept


def _fmt(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, float):
        return "" if math.isnan(value) else f"{value:.4g}"
    return str(value)


def worst_points(rows: Sequence[dict[str, Any]], n: int = WORST_ROWS) -> list[dict[str, Any]]:
    """Return the ``n`` worst points.

    Not completed first (least path completed), then by the worst realised limit ratio
    (highest first).
    """
    def badness(r: dict[str, Any]) -> tuple[int, float, float]:
        pct = r.get("path_completed_pct")
        ratio = r.get("worst_limit_ratio")
        return (0 if r["status"] == "failed" else 1 if r["status"] != "completed" else 2,
                pct if isinstance(pct, float) and not math.isnan(pct) else 0.0,
                -(ratio if isinstance(ratio, float) and not math.isnan(ratio) else 0.0))
    return sorted(rows, key=badness)[:n]


def _table(rows: Sequence[dict[str, Any]], columns: Sequence[str]) -> str:
    head = "".join(f"<th>{html.escape(c)}</th>" for c in columns)
    body = "\n".join(
        "<tr>" + "".join(f"<td>{html.escape(_fmt(r.get(c))[:160])}</td>" for c in columns)
        + "</tr>" for r in rows)
    return f"<table>\n<tr>{head}</tr>\n{body}\n</table>"


_STYLE = """
body { font-family: sans-serif; margin: 2em; max-width: 1200px; }
table { border-collapse: collapse; font-size: 0.85em; }
td, th { border: 1px solid #bbb; padding: 0.2em 0.5em; text-align: right; }
th { background: #eee; }
img { max-width: 100%; }
"""


def render_report(rows: Sequence[dict[str, Any]], meta: dict[str, Any],
                  pngs: dict[str, bytes]) -> str:
    """Return the HTML text of the report (see the module docstring), ``pngs`` inlined."""
    swept = _swept(rows, meta)
    labels = meta.get("labels") or {}
    counts = {s: sum(r["status"] == s for r in rows)
              for s in ("completed", "failed", "interrupted")}
    parts = [
        "<!DOCTYPE html>", "<html><head><meta charset='utf-8'>",
        f"<title>Sweep {html.escape(str(meta.get('name', '')))}</title>",
        f"<style>{_STYLE}</style></head><body>",
        f"<h1>Sweep {html.escape(str(meta.get('name', '')))}</h1>",
        f"<p>{html.escape(str(meta.get('description', '')))}</p>",
        "<p>Base experiment: <code>"
        f"{html.escape(Path(str(meta.get('base', ''))).name)}</code>; swept keys: "
        + ", ".join(f"<code>{html.escape(k)}</code>"
                    + (f" ({html.escape(labels[k])})" if labels.get(k) else "")
                    for k in swept)
        + f"; fixed: <code>{html.escape(json.dumps(meta.get('set', {})))}</code>.</p>",
        f"<p>{len(rows)} points: {counts['completed']} completed, {counts['failed']} "
        f"failed, {counts['interrupted']} not finished.</p>",
    ]
    for name, title in FIGURES:
        data = base64.b64encode(pngs[name]).decode("ascii")
        parts.append(f"<h2>{html.escape(title)}</h2>")
        parts.append(f"<img alt='{html.escape(title)}' src='data:image/png;base64,{data}'>")
    columns = [POINT_COLUMN, *swept, "status", "criterion", "solver", "path_completed_pct",
               "worst_limit_ratio", "recovered_at_s", "worst_limit_ratio_after_recovery",
               "joint_margin_min_rad", "closure_pos_err_max_m", "message"]
    parts.append(f"<h2>The {min(WORST_ROWS, len(rows))} worst points</h2>")
    parts.append(_table(worst_points(rows), columns))
    parts.append("</body></html>")
    return "\n".join(parts) + "\n"


def _write_bytes(path: Path, data: bytes) -> None:
    def write(tmp: str) -> None:
        Path(tmp).write_bytes(data)

    atomic_write_with(path, write)


def write_report(out: Path, meta: dict[str, Any] | None = None) -> Path:
    """Read the table in ``out``; write ``out/report.html`` and the figures' PNG files.

    Each file is written atomically.

    Raises
    ------
    InvalidInputError
        ``out`` holds no sweep results.
    """
    if meta is None:
        meta_path = out / "sweep.json"
        if not meta_path.is_file():
            raise InvalidInputError(f"{out} holds no sweep (sweep.json is missing); run "
                                    "'dualarm-qp sweep SWEEP.yaml --out DIR' first")
        meta = json.loads(meta_path.read_text(encoding="utf-8"))
    rows = read_table(out)
    pngs = draw_figures(rows, _swept(rows, meta, axes=True), meta.get("labels"))
    for name, data in pngs.items():
        _write_bytes(out / name, data)
    path = out / REPORT_FILE
    write_text(path, render_report(rows, meta, pngs))
    return path
