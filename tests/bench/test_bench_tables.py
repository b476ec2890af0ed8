"""The bench and suite tables render aligned text and Markdown from one renderer."""

from __future__ import annotations

from dualarm_qp.bench.report import format_table
from dualarm_qp.bench.suite import format_suite_table
from dualarm_qp.bench.table import render_table


def test_render_table_aligns_labels_left_and_numbers_right():
    text = render_table([["solver", "t"], ["nullspace", "1.5"], ["qp:daqp", "12.25"]])
    assert text.splitlines() == ["solver         t", "nullspace    1.5", "qp:daqp    12.25"]
    md = render_table([["a", "b"], ["x", "1"]], markdown=True)
    assert md.splitlines() == ["| a | b |", "|---|---|", "| x | 1 |"]


def test_suite_and_bench_tables_use_it():
    row = {"solver": "nullspace", "success_rate": 1.0, "success_rate_feasible": 1.0,
           "infeasible_detected": float("nan"), "claimed_true_rate": 1.0,
           "time_median_s": 4.2e-5, "time_p99_s": 1e-4, "sgm_time_rel": 1.0}
    lines = format_suite_table([row]).splitlines()
    assert lines[0].startswith("solver") and lines[1].startswith("nullspace")
    assert " - " in lines[1] + " " and "42.0" in lines[1]
    md = format_suite_table([row], markdown=True).splitlines()
    assert md[1].startswith("|---") and md[2].startswith("| nullspace |")
    bench = format_table([{"experiment": "beam", "solver": "nullspace", "error": "boom"}])
    assert "ERROR" in bench.splitlines()[1]
