"""``report.html``: one self-contained page per run (summary, figures, animation).

The page needs no network and no other file: the figures are inlined as base64 PNG
data, the style sheet is inline, and there is no script. When the run folder holds an
``animation.html``, the page links to it and shows it in a frame, by its relative name
(both files then move together).
"""

from __future__ import annotations

import base64
import html
import json
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from .._io import jsonable, write_text

#: The report's file name in a run folder.
REPORT_FILE = "report.html"

#: The 3D animation's file name, linked when present in the run folder.
ANIMATION_FILE = "animation.html"

_STYLE = """
body { font-family: sans-serif; margin: 1.5em auto; max-width: 1200px; color: #222; }
h1 { font-size: 1.4em; } h2 { font-size: 1.15em; margin-top: 1.6em; }
table { border-collapse: collapse; font-size: 0.9em; margin: 0.4em 0; }
td, th { border: 1px solid #ccc; padding: 0.2em 0.6em; text-align: left;
         vertical-align: top; }
th { background: #f2f2f2; } td.num { text-align: right; font-family: monospace; }
.completed { color: #1a7f37; } .failed, .interrupted { color: #b42318; }
figure { margin: 1em 0; } figure img { max-width: 100%; border: 1px solid #ddd; }
figcaption { font-size: 0.85em; color: #555; }
iframe { width: 100%; height: 640px; border: 1px solid #ccc; }
"""


def _cell(value: Any) -> str:
    """One table cell: numbers right-aligned, lists joined, the rest escaped."""
    if isinstance(value, bool) or value is None:
        return f"<td>{html.escape(str(value))}</td>"
    if isinstance(value, int):
        return f'<td class="num">{value}</td>'
    if isinstance(value, float):
        text = f"{value:.6g}" if math.isfinite(value) else str(value)
        return f'<td class="num">{text}</td>'
    if isinstance(value, list) and all(not isinstance(v, (dict, list)) for v in value):
        return _cell(", ".join(f"{v:.6g}" if isinstance(v, float) else str(v) for v in value))
    if isinstance(value, (dict, list)):
        return f"<td><code>{html.escape(json.dumps(value))}</code></td>"
    return f"<td>{html.escape(str(value))}</td>"


def _flat(d: dict[str, Any], prefix: str = "") -> list[tuple[str, Any]]:
    """Flatten nested dicts into ``(dotted key, value)`` rows."""
    rows: list[tuple[str, Any]] = []
    for key, value in d.items():
        name = f"{prefix}{key}"
        if isinstance(value, dict) and value:
            rows += _flat(value, name + ".")
        else:
            rows.append((name, value))
    return rows


def _table(rows: Sequence[tuple[str, Any]]) -> str:
    body = "".join(f"<tr><th>{html.escape(k)}</th>{_cell(v)}</tr>" for k, v in rows)
    return f"<table>{body}</table>"


def summary_tables(summary: dict[str, Any]) -> str:
    """HTML tables of a run summary: its plain values first, then each nested section."""
    plain = [(k, v) for k, v in summary.items()
             if not isinstance(v, dict) and k != "outputs"]
    parts = ["<h2>Summary</h2>", _table(plain)]
    for key, value in summary.items():
        if isinstance(value, dict) and value:
            parts += [f"<h3>{html.escape(key)}</h3>", _table(_flat(value))]
    return "\n".join(parts)


def _figure(path: Path) -> str:
    data = base64.b64encode(path.read_bytes()).decode("ascii")
    name = html.escape(path.name)
    return (f'<figure id="{name}"><img alt="{name}" src="data:image/png;base64,{data}">'
            f"<figcaption>{name}</figcaption></figure>")


def render_run_report(out: Path, summary: dict[str, Any], figures: Sequence[str]) -> str:
    """Return the report page of the run in folder ``out``.

    Parameters
    ----------
    out : Path
        The run folder: the figures are read from it, and ``animation.html`` is
        linked when it is there.
    summary : dict
        The run summary (the content of ``summary.json``).
    figures : sequence of str
        PNG file names in ``out`` to inline, in order; missing ones are skipped.
    """
    name = f"{summary.get('experiment', '')} ({summary.get('solver', '')})"
    status = str(summary.get("status", ""))
    head = (f"<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<title>{html.escape(name)}</title><style>{_STYLE}</style></head><body>")
    summary = jsonable(summary)
    parts = [head, f"<h1>{html.escape(name)}: <span class=\"{html.escape(status)}\">"
             f"{html.escape(status)}</span></h1>"]
    if summary.get("message"):
        parts.append(f"<p>{html.escape(str(summary['message']))}</p>")
    shown = [f for f in figures if (out / f).is_file()]
    if shown:
        links = " &middot; ".join(f'<a href="#{html.escape(f)}">{html.escape(f)}</a>'
                                  for f in shown)
        parts.append(f"<p>Figures: {links}</p>")
    if (out / ANIMATION_FILE).is_file():
        parts += ["<h2>Animation</h2>",
                  f'<p><a href="{ANIMATION_FILE}">open {ANIMATION_FILE}</a></p>',
                  f'<iframe src="{ANIMATION_FILE}" title="3D animation"></iframe>']
    parts.append(summary_tables(summary))
    if shown:
        parts.append("<h2>Figures</h2>")
        parts += [_figure(out / f) for f in shown]
    parts.append("</body></html>\n")
    return "\n".join(parts)


def write_run_report(out: Path, summary: dict[str, Any] | None = None,
                     figures: Sequence[str] | None = None) -> str:
    """Write ``report.html`` into the run folder ``out``; return its name.

    Parameters
    ----------
    out : Path
        The run folder.
    summary : dict, optional
        The run summary; default: read ``out/summary.json`` (to refresh the report of
        a finished run, e.g. once an animation was written beside it).
    figures : sequence of str, optional
        PNG names to inline; default: the PNG files the summary's ``outputs`` lists.
    """
    if summary is None:
        summary = json.loads((out / "summary.json").read_text())
    if figures is None:
        figures = [f for f in summary.get("outputs", []) if str(f).endswith(".png")]
    write_text(out / REPORT_FILE, render_run_report(out, summary, figures))
    return REPORT_FILE
