"""The reproduction's report.html: one self-contained page that leads to each case, says
how it ended with its key numbers, lists the paper's claims and shows the figures."""

from __future__ import annotations

import base64
import re
from pathlib import Path

from dualarm_qp.experiments.reproduce import CASES, REPRODUCE_FILES
from dualarm_qp.experiments.reproduce_page import (
    CASE_TEXT,
    CLAIM_TEXT,
    render_reproduction_report,
    write_reproduction_report,
)

#: A 1 x 1 PNG.
PIXEL = base64.b64decode("iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAIAAACQd1PeAAAADElEQVR4nGP4"
                         "//8/AAX+Av4N70a4AAAAAElFTkSuQmCC")


def summary(label: str, **extra) -> dict:
    grasp_end = {"a": 0.45, "b": 0.1422, "c": 0.1943, "d": 0.14217}[label]
    return {"experiment": f"beam_{label}", "solver": "nullspace" if label == "d" else "ref",
            "status": "completed", "completed": True, "samples": 501,
            "path_completed_pct": 100.0, "grasp_start_m": 0.45, "grasp_end_m": grasp_end,
            "closure_pos_err_max_m": 1.7e-5,
            "realised_limits": {"follower": {"speed_ratio_max": 8.71}}, **extra}


def check(label: str) -> dict:
    return {"q3_min_deg": -49.9 if label == "a" else -30.94, "q3_max_deg": 6.518,
            "q3_samples_outside": 287 if label == "a" else 0, "q3_first_step_deg": 30.9,
            "grasp_first_step_mm": 258.0}


def folder(tmp_path: Path, labels=("a", "b", "c", "d"), animations=True) -> Path:
    out = tmp_path / "reproduction"
    for label in labels:
        case = out / f"case_{label}"
        case.mkdir(parents=True)
        for name in ("report.html", "summary.json", "trajectory.csv"):
            (case / name).write_text("x")
        if animations:
            (case / "animation.html").write_text("<html></html>")
    for name in ("fig5_joint3.png", "fig6_grasp.png"):
        (out / name).write_bytes(PIXEL)
    (out / "reproduce.json").write_text("{}")
    return out


def record(**changes) -> dict:
    claims = {"case_a_leaves_joint3_range": True, "case_b_joint3_inside": True,
              "case_c_joint3_inside": True, "case_c_moves_less_at_start": False}
    rec = {"status": "completed", "interrupted_case": None,
           "cases": {label: summary(label) for label, _ in CASES},
           "checks": {**{label: check(label) for label, _ in CASES}, "claims": claims},
           "figures": ["fig5_joint3.png", "fig6_grasp.png"]}
    rec.update(changes)
    return rec


def section(page: str, label: str) -> str:
    start = page.index(f'<section id="case_{label}">')
    return page[start:page.index("</section>", start)]


def test_the_page_leads_to_each_case_with_its_numbers(tmp_path):
    out = folder(tmp_path)
    assert write_reproduction_report(out, record()) == "report.html"
    assert "report.html" in REPRODUCE_FILES  # removed with the reproduction it belongs to
    page = (out / "report.html").read_text()
    for label, _ in CASES:
        part = section(page, label)
        assert f'<a href="case_{label}/report.html">' in part
        assert f'<a href="case_{label}/animation.html">' in part
        assert f"beam_{label}" in part and '<span class="completed">completed</span>' in part
        assert CASE_TEXT[label].replace("'", "&#x27;") in part
        assert "501 samples, 100% of the path" in part
    assert "287 samples outside its range" in section(page, "a")
    assert "grasp 450 mm -&gt; 142.2 mm" in section(page, "b")
    assert "grasp 450 mm -&gt; 194.3 mm" in section(page, "c")
    assert "8.71 times its speed limit" in section(page, "d")
    claims = page[page.index('<table class="claims">'):]
    assert claims.count("<tr>") == 5
    assert f'<td class="failed">NO</td><td>{CLAIM_TEXT["case_c_moves_less_at_start"]}' in claims
    assert '<a href="reproduce.json">' in page


def test_the_page_is_self_contained(tmp_path):
    out = folder(tmp_path)
    page = render_reproduction_report(out, record())
    assert page.count('src="data:image/png;base64,') == 2
    assert base64.b64encode(PIXEL).decode() in page
    refs = re.findall(r"""(?:src|href)\s*=\s*["']?([^"'\s>]+)""", page, flags=re.I)
    assert refs, "no reference found at all: the pattern is wrong"
    assert not [r for r in refs if re.match(r"(https?:)?//", r, flags=re.I)]
    local = [r for r in refs if not r.startswith(("data:", "#"))]
    assert all((out / r).is_file() for r in local), local  # every link leads to a file
    assert "<script" not in page.lower() and "@import" not in page


def test_a_case_that_failed_says_why_and_missing_files_are_not_linked(tmp_path):
    out = folder(tmp_path, animations=False)
    failed = summary("d", status="failed", completed=False,
                     message="closure error 2 mm at sample 3",
                     failure={"criterion": "closure"})
    page = render_reproduction_report(out, record(
        status="failed", cases={**record()["cases"], "d": failed}))
    part = section(page, "d")
    assert '<span class="failed">failed</span>: <code>closure</code>' in part
    assert "closure error 2 mm at sample 3" in part
    assert "animation.html" not in page


def test_an_interrupted_reproduction_shows_the_cases_it_ran(tmp_path):
    out = folder(tmp_path, labels=("a", "b"))
    for name in ("fig5_joint3.png", "fig6_grasp.png"):
        (out / name).unlink()
    cases = {"a": summary("a"), "b": summary("b", status="interrupted",
                                             failure={"criterion": "interrupted"})}
    page = render_reproduction_report(out, record(
        status="interrupted", interrupted_case="b", cases=cases, checks={},
        figures=[]))
    assert "Interrupted in case (b)" in page
    assert re.findall(r'<section id="case_(\w)">', page) == ["a", "b"]
    assert "the run was interrupted" in section(page, "b")
    assert "<figure" not in page and "claims" not in page


def test_a_case_stopped_before_its_first_sample_has_no_numbers(tmp_path):
    """0 samples: no grasp (NaN in the summary, null in reproduce.json) and no speeds."""
    out = folder(tmp_path, labels=("a",))
    empty = summary("a", status="interrupted", samples=0, path_completed_pct=0.0,
                    grasp_start_m=float("nan"), grasp_end_m=float("nan"),
                    closure_pos_err_max_m=None, realised_limits={},
                    failure={"criterion": "interrupted"})
    page = render_reproduction_report(out, record(
        status="interrupted", interrupted_case="a", cases={"a": empty}, checks={},
        figures=[]))
    part = section(page, "a")
    assert "0 samples, 0% of the path" in part and "grasp n/a -&gt; n/a" in part
    assert "worst closure error n/a" in part
