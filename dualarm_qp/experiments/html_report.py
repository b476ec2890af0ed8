"""``report.html``: one self-contained page per run (verdict, figures, animation, values).

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

#: The style sheet of the report pages (inline: the pages need no other file).
STYLE = """
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
.verdict { font-size: 1.05em; padding: 0.5em 0.8em; border-left: 5px solid; }
.verdict.completed { border-color: #1a7f37; background: #eef8f0; color: #222; }
.verdict.failed, .verdict.interrupted { border-color: #b42318; background: #fdf0ef;
                                        color: #222; }
td.over { color: #b42318; font-weight: bold; } .note { font-size: 0.85em; color: #555; }
details { margin-top: 2em; } summary { cursor: pointer; font-weight: bold; }
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


#: What each failure criterion means, for the verdict (the message gives the numbers).
CRITERION_TEXT = {
    "solver": "a step could not be solved",
    "support": "the supporting follower lost its support",
    "closure": "the grasp closure error passed its tolerance",
    "tracking": "the leader left the path D(t) by more than its tolerance",
    "singularity": "an arm came too near a singularity",
    "stalled": "the path stalled: the limits stopped the object",
    "path_incomplete": "the path was not finished within the duration cap",
    "range": "the realised motion left a range",
    "speed": "the realised motion broke a speed limit",
    "acceleration": "the realised motion broke an acceleration limit",
    "jerk": "the realised motion broke a jerk limit",
    "watchdog": "the robots' state stopped coming (the cell's watchdog)",
    "start": "the robots were not at the file's start",
    "cell": "the cell stopped answering",
    "interrupted": "the run was interrupted",
    "collision": "a pair of bodies blocked the task or came closer than the safety distance",
    "path_collision": "the path D(t) carries the object into an obstacle",
}

#: What each figure of a run shows (its caption in the report).
FIGURE_CAPTIONS = {
    "joints.png": "Joints against their ranges: one lane per joint (leader above, follower "
                  "below), scaled so that each joint's range lies on its lane's dashed "
                  "lines (the label beside it gives the range); shaded where outside.",
    "rates.png": "Joint rates, commanded and realised, against the speed limits: one lane "
                 "per joint, the limits on its dashed lines (the label gives them); shaded "
                 "where the realised rate is over.",
    "grasp.png": "Grasp position along the object against its range; sliding speed "
                 "against its limit.",
    "tracking.png": "Leader's error to D(t) against its tolerance, the arms' smallest "
                    "singular values, and the task scale (below 1: the limits slowed "
                    "the path).",
    "closure.png": "Grasp closure error (Eq. 15) against its tolerance.",
    "clearance.png": "Smallest distance of each group of pairs against the safety distance "
                     "d_s (dashed; with collision avoidance on, the run fails below d_s "
                     "less the allowance, dotted) and the influence distance d_i (pairs "
                     "closer get a row in the step); the smallest is marked with its pair.",
    "physics.png": "Physics check (MuJoCo): rigid replay and closed loop against the "
                   "thresholds (docs/physics.md).",
}

#: The limit groups of ``realised_limits``, in the order shown, with their names.
_PARTS = {"leader": "leader arm", "follower": "follower arm", "grasp": "follower grasp",
          "grasp_leader": "leader grasp"}

#: The entries of ``realised_limits`` that are no range and speed of a variable (shown
#: on their own).
_NOT_RANGES = ("clearance", "torque")


def _figure(path: Path) -> str:
    data = base64.b64encode(path.read_bytes()).decode("ascii")
    name = html.escape(path.name)
    caption = html.escape(FIGURE_CAPTIONS.get(path.name, ""))
    return (f'<figure id="{name}"><img alt="{name}" src="data:image/png;base64,{data}">'
            f"<figcaption>{name}{': ' + caption if caption else ''}</figcaption></figure>")


def _num(value: Any, unit: str = "", digits: int = 3) -> str:
    """Return a number for a person (``n/a`` when missing)."""
    if not isinstance(value, (int, float)) or isinstance(value, bool) or value != value:
        return "n/a"
    return f"{value:.{digits}g}{' ' + unit if unit else ''}"


def _share(ratio: Any) -> str:
    """Return a ratio to a limit as a percentage table cell (over 100%: marked)."""
    if not isinstance(ratio, (int, float)) or ratio != ratio:
        return "<td>no limit</td>"
    over = ' class="over"' if ratio > 1.0 + 1e-9 else ""
    return f'<td{over}>{100.0 * ratio:.3g}%</td>'


def _variable(name: Any, summary: dict[str, Any]) -> str:
    """Name a limited variable (``qf2``), with the arm's joint name when it has one."""
    text = str(name or "")
    role = {"ql": "leader", "qf": "follower"}.get(text[:2])
    if role is not None and text[2:].isdigit():
        names = summary.get("arms", {}).get(role, {}).get("joint_names", [])
        j = int(text[2:]) - 1
        if 0 <= j < len(names) and names[j] != f"joint{j + 1}":
            return f"{text} ({names[j]})"
    return text


def verdict(summary: dict[str, Any]) -> str:
    """Return the run's verdict: completed, or failed (or interrupted) and why (HTML)."""
    status = str(summary.get("status", "completed" if summary.get("completed") else "failed"))
    failure = summary.get("failure") or {}
    if status == "completed":
        text = ("<strong>Completed</strong>: the whole path D(t) was carried out within "
                "the tolerances" + (" and every limit the solver enforces"
                                    if summary.get("hard_limits") else "") + ".")
    else:
        criterion = str(failure.get("criterion", ""))
        why = CRITERION_TEXT.get(criterion, criterion)
        text = (f"<strong>{html.escape(status.upper())}</strong> on "
                f"<code>{html.escape(criterion)}</code>: {html.escape(why)}.<br>"
                f"{html.escape(str(summary.get('message', '')))}")
    return f'<p id="verdict" class="verdict {html.escape(status)}">{text}</p>'


def glance(summary: dict[str, Any]) -> str:
    """Return the few numbers that say how the run went (HTML table)."""
    settings = summary.get("settings", {})
    tol = summary.get("tracking_tolerance_m_rad") or [None, None]
    ctol = summary.get("closure_tolerance_m_rad") or [None, None]
    lost = summary.get("time_lost_to_scaling_s")
    counts = summary.get("status_counts", {})
    rows = [
        ("path done", f"{_num(summary.get('path_completed_pct'), digits=4)}% of D(t): "
                      f"path time {_num(summary.get('path_time_end_s'), digits=4)} s of "
                      f"{_num(settings.get('duration_s'), 's', 4)}, in "
                      f"{summary.get('samples', 'n/a')} samples of "
                      f"{_num(settings.get('dt_s'), 's')}"),
        ("time lost to slowing", ("none" if lost == 0 else _num(lost, "s"))
         + " (the limits slowed the path by this much)" * bool(lost)),
        ("leader's error to D(t), worst",
         f"{_num(summary.get('leader_pos_err_max_m'), 'm')}, "
         f"{_num(summary.get('leader_rot_err_max_rad'), 'rad')} (tolerance "
         f"{_num(tol[0], 'm')}, {_num(tol[1], 'rad')})"),
        ("grasp closure error, worst",
         f"{_num(summary.get('closure_pos_err_max_m'), 'm')}, "
         f"{_num(summary.get('closure_rot_err_max_rad'), 'rad')} (tolerance "
         f"{_num(ctol[0], 'm')}, {_num(ctol[1], 'rad')})"),
        ("steps", ", ".join(f"{n} {k}" for k, n in counts.items())
         + (f"; {summary['fallback_steps']} by the fallback solver"
            if summary.get("fallback_steps") else "")),
        ("solver", f"{summary.get('solver', '')}: "
                   + ("enforces the limits (hard)" if summary.get("hard_limits")
                      else "does not enforce the limits")),
    ]
    body = "".join(f"<tr><th>{html.escape(k)}</th><td>{html.escape(v)}</td></tr>"
                   for k, v in rows)
    return f'<table class="glance">{body}</table>'


def limits_table(summary: dict[str, Any]) -> str:
    """Worst realised share of each limit, range and speed, per arm and grasp (HTML)."""
    realised = summary.get("realised_limits") or {}
    head = ("<tr><th></th><th colspan=\"2\">range</th><th colspan=\"2\">speed</th></tr>"
            "<tr><th></th><th>worst</th><th>where</th><th>worst</th><th>where</th></tr>")
    rows = []
    ranged = {k: v for k, v in realised.items() if k not in _NOT_RANGES}
    for part, r in sorted(ranged.items(), key=lambda kv: list(_PARTS).index(kv[0])
                          if kv[0] in _PARTS else len(_PARTS)):
        start = r.get("range_ratio_start")
        started = (f"; started outside, at {100.0 * start:.3g}%"
                   if isinstance(start, (int, float)) and start > 1.0 + 1e-9 else "")
        speed = r.get("speed_ratio_max")
        limited = isinstance(speed, (int, float)) and speed == speed
        fastest = _variable(r.get("worst_speed"), summary) if limited else ""
        rows.append(f"<tr><th>{html.escape(_PARTS.get(part, part))}</th>"
                    f"{_share(r.get('range_ratio_max'))}"
                    f"<td>{html.escape(_variable(r.get('worst_range'), summary) + started)}"
                    f"</td>{_share(speed)}<td>{html.escape(fastest)}</td></tr>")
    note = ("Range: 100% is at a limit (0% mid-range), above 100% outside. Speed: the "
            "share of the speed limit, from the recorded motion. "
            + ("The solver enforces the limits: a variable that starts outside its range "
               "may not move further out." if summary.get("hard_limits") else
               "This solver does not enforce the limits: shares above 100% are expected."))
    return (f'<table class="limits">{head}{"".join(rows)}</table>'
            f'<p class="note">{html.escape(note)}</p>')


def _mm(value: Any) -> str:
    """Return a length [m] in millimetres for a person (``n/a`` when missing)."""
    if not isinstance(value, (int, float)) or isinstance(value, bool) or value != value:
        return "n/a"
    return f"{value * 1e3:.4g} mm"


def clearance_text(summary: dict[str, Any]) -> str | None:
    """Return the run's smallest clearance against the safety distance (plain text).

    None when the run had no collision scene (no ``realised_limits.clearance``).
    """
    c = (summary.get("realised_limits") or {}).get("clearance")
    if not isinstance(c, dict):
        return None
    if c.get("min_m") is None:
        return "no pair measured"
    ds, allowance = c.get("safety_distance_m"), c.get("allowance_m")
    verdict = ("kept" if c.get("kept") else "NOT kept") + (
        " (the step kept it)" if c.get("enforced") else
        " (collision avoidance off: measured only)")
    return (f"{_mm(c.get('min_m'))}, {c.get('pair', '')} (sample {c.get('sample')}); safety "
            f"distance {_mm(ds)}, allowance {_mm(allowance)}: {verdict}"
            + ("; the shapes overlap" if c.get("penetration") else ""))


def render_run_report(out: Path, summary: dict[str, Any], figures: Sequence[str]) -> str:
    """Return the report page of the run in folder ``out``.

    The page leads with what a person asks first: the verdict (completed, or failed
    with the criterion and the message), the path done, the time lost, the errors, the
    worst realised share of each limit with its joint, any warnings, then the figures
    and the animation. Every value of ``summary.json`` follows, folded.

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
            f"<title>{html.escape(name)}</title><style>{STYLE}</style></head><body>")
    summary = jsonable(summary)
    parts = [head, f"<h1>{html.escape(name)}: <span class=\"{html.escape(status)}\">"
             f"{html.escape(status)}</span></h1>", verdict(summary), glance(summary)]
    if summary.get("realised_limits"):
        parts += ["<h2>Limits: the worst realised share of each</h2>", limits_table(summary)]
    clearance = clearance_text(summary)
    if clearance is not None:
        parts += ['<h2>Clearance: the smallest distance between bodies</h2>',
                  f'<p id="clearance">{html.escape(clearance)}</p>']
    if isinstance(summary.get("physics"), dict):  # dualarm-qp physics RUN_DIR
        from ..physics.report import physics_html

        parts.append(physics_html(summary["physics"]))
    if summary.get("warnings"):
        parts += ["<h2>Warnings</h2>", "<ul>" + "".join(
            f"<li>{html.escape(str(w))}</li>" for w in summary["warnings"]) + "</ul>"]
    shown = [f for f in figures if (out / f).is_file()]
    if shown:
        links = " &middot; ".join(f'<a href="#{html.escape(f)}">{html.escape(f)}</a>'
                                  for f in shown)
        parts += ["<h2>Figures</h2>", f"<p>{links}</p>"]
        parts += [_figure(out / f) for f in shown]
    if (out / ANIMATION_FILE).is_file():
        parts += ["<h2>Animation</h2>",
                  f'<p><a href="{ANIMATION_FILE}">open {ANIMATION_FILE}</a></p>',
                  f'<iframe src="{ANIMATION_FILE}" title="3D animation"></iframe>']
    parts += ['<details id="all-values"><summary>Every value of summary.json</summary>',
              summary_tables(summary), "</details>"]
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
