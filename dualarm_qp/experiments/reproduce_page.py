"""``report.html`` of a reproduction: one page that leads to each case.

``dualarm-qp reproduce --out DIR`` writes four case folders (each with its own
``report.html`` and ``animation.html``), two figures and ``reproduce.json``. This page,
``DIR/report.html``, says what each case is, whether it completed and its key numbers,
links each case's report and animation (relative links: the folder moves as a whole),
lists the paper's claims as checked, and shows Figs. 5 and 6. Like a run's report it
needs no network: the figures are inlined as base64 PNG data, the style sheet is inline,
and there is no script.

The page is rendered from the record that ``reproduce.json`` holds, so it says what that
file says; it is written just before it, atomically.
"""

from __future__ import annotations

import base64
import html
import math
from pathlib import Path
from typing import Any

from .._io import jsonable, write_text
from .html_report import ANIMATION_FILE, CRITERION_TEXT, REPORT_FILE, STYLE

#: What each case is (the case folder is ``case_<label>``).
CASE_TEXT = {
    "a": "The paper's case (a): the follower's grasp held at 450 mm on the beam (the "
         "fixed-grasp step). Fig. 5: its joint 3 leaves its range.",
    "b": "The paper's case (b): the grasp slides along the beam, sliding weight s7 = 100, "
         "the paper's pseudoinverse step (no limits). Joint 3 stays inside its range.",
    "c": "The paper's case (c): as (b) with s7 = 1000: the grasp moves less at the start.",
    "d": "Not in the paper: case (b) with joint and sliding speed limits, kept by the "
         "hard-limit nullspace solver (no first-sample jump).",
}

#: What each of the paper's claims says (``checks.claims`` of ``reproduce.json``).
CLAIM_TEXT = {
    "case_a_leaves_joint3_range": "(a) with the grasp fixed, follower joint 3 leaves its "
                                  "range (Fig. 5)",
    "case_b_joint3_inside": "(b) with the grasp sliding, joint 3 stays inside its range",
    "case_c_joint3_inside": "(c) likewise, with the heavier sliding weight",
    "case_c_moves_less_at_start": "(c) moves less than (b) at the start: grasp travel over "
                                  "the first 10 samples (Fig. 6)",
}

#: What each figure of the reproduction shows.
FIGURE_TEXT = {
    "fig5_joint3.png": "Fig. 5: follower joint 3 of every case against its range, and its "
                       "realised rate against case (d)'s speed limit; right, the first 0.5 s.",
    "fig6_grasp.png": "Fig. 6: the grasp position of the sliding cases against the grasp "
                      "range, and its realised speed against case (d)'s sliding speed "
                      "limit; right, the first 0.5 s.",
}


def _num(value: Any, unit: str = "", digits: int = 4, scale: float = 1.0) -> str:
    """Return ``scale * value`` for a person (``n/a`` when missing).

    A value is missing when absent, null or not finite: ``reproduce.json`` holds null
    for a number a case never reached (a case stopped before its first sample has no
    grasp position), and ``scale`` (e.g. 1e3 for m to mm) is applied only after the check.
    """
    if not isinstance(value, (int, float)) or isinstance(value, bool) or not math.isfinite(
            value):
        return "n/a"
    return f"{scale * value:.{digits}g}{' ' + unit if unit else ''}"


def _status(summary: dict[str, Any]) -> str:
    """Return the case's outcome: completed, or failed (interrupted) and why (HTML)."""
    status = str(summary.get("status", ""))
    text = f'<span class="{html.escape(status)}">{html.escape(status)}</span>'
    failure = summary.get("failure") or {}
    if status != "completed" and failure.get("criterion"):
        criterion = str(failure["criterion"])
        text += (f": <code>{html.escape(criterion)}</code>, "
                 f"{html.escape(CRITERION_TEXT.get(criterion, criterion))}")
    return text


def _numbers(summary: dict[str, Any], check: dict[str, Any]) -> list[str]:
    """Return the key numbers of one case (plain text, one item each)."""
    follower = (summary.get("realised_limits") or {}).get("follower") or {}
    items = [f"{summary.get('samples', 'n/a')} samples, "
             f"{_num(summary.get('path_completed_pct'))}% of the path"]
    if check:
        items.append(f"follower q3 from {_num(check.get('q3_min_deg'), 'deg')} to "
                     f"{_num(check.get('q3_max_deg'), 'deg')}; "
                     f"{check.get('q3_samples_outside', 'n/a')} samples outside its range")
    items.append(f"grasp {_num(summary.get('grasp_start_m'), 'mm', scale=1e3)} -> "
                 f"{_num(summary.get('grasp_end_m'), 'mm', scale=1e3)}")
    if check and "q3_first_step_deg" in check:
        items.append(f"first sample: q3 moves {_num(check['q3_first_step_deg'], 'deg', 3)}, "
                     f"the grasp {_num(check.get('grasp_first_step_mm'), 'mm', 3)}")
    items.append(f"worst closure error {_num(summary.get('closure_pos_err_max_m'), 'm', 2)}; "
                 f"fastest follower joint at {_num(follower.get('speed_ratio_max'), '', 3)} "
                 "times its speed limit (realised)")
    return items


def _links(out: Path, label: str) -> str:
    """Return links to the files of case ``label`` that are in its folder (HTML)."""
    folder = f"case_{label}"
    names = [(REPORT_FILE, "report"), (ANIMATION_FILE, "3D animation"),
             ("summary.json", "summary.json"), ("trajectory.csv", "trajectory.csv")]
    links = [f'<a href="{folder}/{name}">{text}</a>' for name, text in names
             if (out / folder / name).is_file()]
    return " &middot; ".join(links) if links else "no files"


def _case(out: Path, label: str, summary: dict[str, Any], check: dict[str, Any]) -> str:
    """Return one case's section (HTML)."""
    title = (f"Case ({html.escape(label)}): {html.escape(str(summary.get('experiment', '')))}"
             f" [{html.escape(str(summary.get('solver', '')))}]")
    message = ("" if summary.get("status") == "completed"
               else f'<p class="note">{html.escape(str(summary.get("message", "")))}</p>')
    numbers = "".join(f"<li>{html.escape(item)}</li>" for item in _numbers(summary, check))
    return (f'<section id="case_{html.escape(label)}"><h2>{title}: {_status(summary)}</h2>'
            f"<p>{html.escape(CASE_TEXT.get(label, ''))}</p>{message}<ul>{numbers}</ul>"
            f"<p>{_links(out, label)}</p></section>")


def _claims(claims: dict[str, Any]) -> str:
    """Return the paper's claims as checked (HTML table)."""
    rows = "".join(
        f'<tr><td class="{"completed" if held else "failed"}">{"yes" if held else "NO"}</td>'
        f"<td>{html.escape(CLAIM_TEXT.get(name, name.replace('_', ' ')))}</td></tr>"
        for name, held in claims.items())
    return f'<table class="claims"><tr><th>holds</th><th>claim</th></tr>{rows}</table>'


def _figure(path: Path) -> str:
    data = base64.b64encode(path.read_bytes()).decode("ascii")
    name = html.escape(path.name)
    return (f'<figure id="{name}"><img alt="{name}" src="data:image/png;base64,{data}">'
            f"<figcaption>{name}: {html.escape(FIGURE_TEXT.get(path.name, ''))}"
            "</figcaption></figure>")


def render_reproduction_report(out: Path, record: dict[str, Any]) -> str:
    """Return the page of the reproduction in folder ``out``.

    Parameters
    ----------
    out : Path
        The reproduction's folder: the figures are read from it, and each case's files
        are linked when they are in ``out/case_<label>``.
    record : dict
        What ``reproduce.json`` holds: ``status``, ``interrupted_case``, ``cases`` (each
        case's run summary by label), ``checks`` (by label, and ``claims``),
        ``figures`` (PNG names in ``out``).
    """
    record = jsonable(record)
    status = str(record.get("status", ""))
    cases = record.get("cases") or {}
    checks = record.get("checks") or {}
    title = "Reproduction of Suh and Shin (1988), Sec. 4: the PUMA 560 beam"
    parts = [f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
             f"<title>{html.escape(title)}</title><style>{STYLE}</style></head><body>",
             f'<h1>{html.escape(title)}: <span class="{html.escape(status)}">'
             f"{html.escape(status)}</span></h1>",
             "<p>Four runs of one task: two PUMA 560 arms carry a beam, the leader holding "
             "one end along a straight path D(t) (500 mm in 15.5 s), the follower the "
             "other, its grasp free to slide along the beam in cases (b), (c) and (d). "
             "Each case's own report has its figures, its limits and every value of its "
             "summary.</p>"]
    if record.get("interrupted_case") is not None:
        parts.append(f'<p class="verdict interrupted">Interrupted in case '
                     f"({html.escape(str(record['interrupted_case']))}): the cases below are "
                     "the ones run; no figure was drawn and no claim checked.</p>")
    links = " &middot; ".join(f'<a href="#case_{html.escape(k)}">case ({html.escape(k)})</a>'
                              for k in cases)
    parts.append(f"<p>{links}</p>")
    parts += [_case(out, label, summary, checks.get(label) or {})
              for label, summary in cases.items()]
    if checks.get("claims"):
        parts += ["<h2>The paper's claims</h2>", _claims(checks["claims"])]
    shown = [f for f in record.get("figures") or [] if (out / f).is_file()]
    if shown:
        parts += ["<h2>Figures</h2>"] + [_figure(out / f) for f in shown]
    parts.append('<p class="note">Every number of every case, and the checks: '
                 '<a href="reproduce.json">reproduce.json</a>.</p></body></html>\n')
    return "\n".join(parts)


def write_reproduction_report(out: Path, record: dict[str, Any]) -> str:
    """Write ``report.html`` into the reproduction's folder ``out`` (atomically).

    Returns
    -------
    str
        The file's name.
    """
    write_text(out / REPORT_FILE, render_reproduction_report(out, record))
    return REPORT_FILE


__all__ = ["CASE_TEXT", "CLAIM_TEXT", "render_reproduction_report",
           "write_reproduction_report"]
