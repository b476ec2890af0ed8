"""The bench and suite tables render aligned text and Markdown from one renderer."""

from __future__ import annotations

from dualarm_qp.bench.report import TABLE, format_table, jobs_line, table_legend
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


def test_every_column_of_the_bench_table_has_a_legend_entry():
    legend = table_legend()
    entries = [line.strip() for line in legend.splitlines()[1:] if line.startswith("  ")
               and not line.startswith("   ")]
    named = {h.strip() for entry in entries for h in entry.split(":")[0].split(",")}
    assert named == {h for h, _, _ in TABLE[2:]}  # all but config and solver
    assert all(len(line) <= 100 for line in legend.splitlines())
    text = " ".join(legend.split())
    assert "solve/bare: qp:* solvers only: our whole solve over the backend's own" in text
    assert "margin rad: smallest distance of a follower joint" in text
    assert "negative: outside" in text


def test_the_jobs_line_says_what_was_computed_and_what_was_reused():
    assert jobs_line(11, 11, 11) == "11 of 11 jobs computed now"  # nothing resumed
    assert jobs_line(0, 11, 11) == "0 of 11 jobs computed now, 11 reused from the store " \
                                   "(resumed)"
    assert jobs_line(4, 11, 11) == "4 of 11 jobs computed now, 7 reused from the store " \
                                   "(resumed)"
    assert jobs_line(2, 5, 11) == ("2 of 11 jobs computed now, 3 reused from the store "
                                   "(resumed), 6 not run")  # interrupted
    assert jobs_line(1, 1, 1) == "1 of 1 job computed now"
