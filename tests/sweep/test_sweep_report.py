"""The report: self-contained HTML, maps over any kind of key; imports stay lazy."""

from __future__ import annotations

import json
import math
import subprocess
import sys

import pytest

from dualarm_qp.sweep.labels import axis_label, file_units, sweep_labels
from dualarm_qp.sweep.maps import completion_figure, limits_figure, solver_figure
from dualarm_qp.sweep.points import START_UNREACHABLE, PointTask
from dualarm_qp.sweep.report import _swept, draw_figures, render_report, worst_points
from dualarm_qp.sweep.table import build_rows, read_table, write_table
from dualarm_qp.sweep.worker import empty_record


def _rows(values: list[dict], statuses: list[str]) -> tuple[list[dict], list[str]]:
    swept = list(values[0])
    tasks = [PointTask(i, f"k{i}", v, {}, "base.yaml", 1) for i, v in enumerate(values)]
    records = {}
    for i, status in enumerate(statuses):
        if status == "interrupted":
            continue
        rec = empty_record(status, None if status == "completed" else "stalled", "")
        rec.update(key=f"k{i}", solver=values[i].get("solver.name", "nullspace"),
                   path_completed_pct=100.0 if status == "completed" else 10.0 * i,
                   worst_limit_ratio=0.5 + 0.1 * i, joint_margin_min_rad=0.1 - 0.01 * i)
        records[f"k{i}"] = rec
    return build_rows(tasks, swept, records), swept


@pytest.mark.parametrize("values", [
    [{"a.0": x, "b": y} for x in (1, 2, 3) for y in (0.5, 1.5)],           # a full grid
    [{"a.0": 0.1 * i, "b": 0.37 * i % 1} for i in range(6)],               # scattered
    [{"solver.name": s, "v": x} for s in ("nullspace", "qp:daqp") for x in (1, 2, 3)],
    [{"v": x} for x in range(6)],                                          # one key
])
@pytest.mark.slow
def test_report_draws_every_kind_of_sweep_into_one_file(tmp_path, values):
    statuses = ["completed", "failed", "completed", "interrupted", "failed", "completed"]
    rows, swept = _rows(values, statuses)
    write_table(tmp_path, rows, swept)
    back = read_table(tmp_path)
    assert [r["point"] for r in back] == list(range(6))
    assert [r["status"] for r in back] == statuses
    assert math.isnan(back[3]["path_completed_pct"])
    pngs = draw_figures(back, swept)
    assert all(data.startswith(b"\x89PNG") for data in pngs.values())
    html = render_report(back, {"name": "t", "swept_keys": swept}, pngs)
    assert html.count("data:image/png;base64,") == 3
    assert "src='http" not in html and "<script" not in html and "<link" not in html


def test_worst_points_put_failures_first():
    rows, _ = _rows([{"x": i} for i in range(6)],
                    ["completed", "failed", "completed", "interrupted", "failed", "completed"])
    worst = worst_points(rows, 4)
    assert [r["point"] for r in worst] == [1, 4, 3, 5]


@pytest.mark.slow
def test_importing_the_sweep_package_imports_no_dask_pyarrow_or_matplotlib():
    code = ("import sys, dualarm_qp.sweep\n"
            "bad = [m for m in ('dask', 'distributed', 'pyarrow', 'matplotlib') "
            "if m in sys.modules]\n"
            "assert not bad, bad\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120, check=False)
    assert proc.returncode == 0, proc.stderr


def test_categories_keep_the_sweep_files_order_not_the_texts():
    values = [{"follower.base.position": p, "b": y}
              for p in ([5, 0, 0], [10, 0, 0], [3, 0, 0]) for y in (1, 2)]
    rows, swept = _rows(values, ["completed"] * 6)
    rows = [{**r, "follower.base.position": json.dumps(r["follower.base.position"])}
            for r in rows]  # as the table holds them: JSON text
    ax = completion_figure(rows, swept).axes[0]
    assert [t.get_text() for t in ax.get_xticklabels()] == [  # as text: 10, 3, 5
        "[5, 0, 0]", "[10, 0, 0]", "[3, 0, 0]"]


@pytest.mark.slow
def test_the_start_unreachable_legend_covers_no_map():
    values = [{"x": x, "y": y} for x in (0, 1, 2, 3) for y in (0, 1, 2, 3)]
    rows, swept = _rows(values, ["completed"] * 16)
    for r in rows[-4:]:  # the top-right corner, where the legend used to sit
        r.update(status="failed", criterion=START_UNREACHABLE, path_completed_pct=0.0)
    for fig in (completion_figure(rows, swept), limits_figure(rows, swept)):
        fig.canvas.draw()
        (legend,) = fig.legends
        assert "start unreachable" in [t.get_text() for t in legend.get_texts()]
        box = legend.get_window_extent()
        assert not any(box.overlaps(ax.get_window_extent()) for ax in fig.axes)
        assert not any(ax.get_legend() for ax in fig.axes)


def test_axis_labels_name_the_key_and_its_unit_in_the_files_units():
    mm = file_units({"units": {"length": "mm", "angle": "deg"}})
    assert axis_label("follower.base.position.0", mm) == "follower base x [mm]"
    assert axis_label("follower.base.position.1", file_units({})) == "follower base y [m]"
    assert axis_label("trajectory.velocity.0", mm) == "object velocity x [mm/s]"
    assert axis_label("leader.qd_max.2", mm) == "leader q3 speed limit [deg/s]"
    assert axis_label("controller.duration", mm) == "duration [s]"
    assert axis_label("solver.name", mm) == "solver"
    assert axis_label("controller.weights.leader_joints", mm) == \
        "controller weights leader joints"  # no rule: the path, no unit
    labels = sweep_labels(["a.b", "controller.dt"], mm, {"a.b": "my a"})
    assert labels == {"a.b": "my a", "controller.dt": "sampling interval [s]"}


def test_maps_show_the_labels():
    rows, swept = _rows([{"a.0": x, "v": y} for x in (1, 2, 3) for y in (1, 2)],
                        ["completed"] * 6)
    labels = {"a.0": "follower base x [mm]", "v": "object velocity x [mm/s]"}
    ax = completion_figure(rows, swept, labels).axes[0]
    assert (ax.get_xlabel(), ax.get_ylabel()) == tuple(labels.values())
    fig = solver_figure(rows, swept, labels)
    assert fig.axes[0].get_xlabel() == labels["a.0"]
    assert fig.axes[0].get_title() == "Success by solver against follower base x [mm]"


def test_the_limit_maps_circle_points_that_never_got_inside_their_ranges():
    rows, swept = _rows([{"x": x, "y": y} for x in (0, 1) for y in (0, 1)], ["completed"] * 4)
    for i, r in enumerate(rows):
        r.update(recovered_at_s=0.5 * i, worst_limit_ratio_after_recovery=0.9,
                 joint_margin_min_after_recovery_rad=0.1)
    rows[3].update(recovered_at_s=math.nan, worst_limit_ratio_after_recovery=math.nan,
                   joint_margin_min_after_recovery_rad=math.nan)
    fig = limits_figure(rows, swept)
    circled = [ln for ax in fig.axes for ln in ax.lines if ln.get_label() ==
               "never inside every range"]
    assert len(circled) == 3  # on each of the three maps, at the one point
    assert {(tuple(ln.get_xdata()), tuple(ln.get_ydata())) for ln in circled} == {((1.0,),
                                                                                    (1.0,))}


def test_maps_are_drawn_over_the_free_keys_not_the_paired_ones():
    rows, swept = _rows([{"v": v, "solver.name": s, "duration": 40 / v}
                         for v in (10, 20) for s in ("a", "b")], ["completed"] * 4)
    meta = {"swept_keys": swept, "map_keys": ["v", "solver.name"]}
    assert _swept(rows, meta, axes=True) == ["v", "solver.name"]
    assert _swept(rows, meta) == ["v", "solver.name", "duration"]  # the table's columns


@pytest.mark.parametrize("n", [2, 3, 5])
def test_a_grid_shows_every_sampled_point_on_axes_that_span_them(n):
    """A small grid is squares at its points, not one block of colour reaching beyond
    them; every point is marked by its outcome; the axes stop just past the samples."""
    from matplotlib.collections import QuadMesh

    from dualarm_qp.sweep.maps import MARGIN, MIN_CELL_LEVELS

    xs, ys = [0.1 * i for i in range(n)], [100.0 + 50.0 * j for j in range(n)]
    statuses = ["completed"] * (n * n)
    statuses[1] = "failed"  # at (xs[0], ys[1])
    rows, swept = _rows([{"x": x, "y": y} for x in xs for y in ys], statuses)
    rows[-1].update(criterion=START_UNREACHABLE, status="failed", path_completed_pct=0.0)
    for r in rows:
        r.update(recovered_at_s=0.2, worst_limit_ratio_after_recovery=0.9,
                 joint_margin_min_after_recovery_rad=0.1)
    for fig in (completion_figure(rows, swept), limits_figure(rows, swept)):
        maps = [ax for ax in fig.axes if ax.get_label() != "<colorbar>"]
        assert len(maps) in (1, 3)
        for ax in maps:
            cells = [c for c in ax.collections if isinstance(c, QuadMesh)]
            assert bool(cells) == (n >= MIN_CELL_LEVELS)
            for (lo, hi), sampled in ((ax.get_xlim(), xs), (ax.get_ylim(), ys)):
                span = max(sampled) - min(sampled)
                assert lo < min(sampled) and hi > max(sampled)
                assert hi - lo == pytest.approx((1 + 2 * MARGIN) * span)
            marked = {gid: set(zip(ln.get_xdata(), ln.get_ydata(), strict=True))
                      for ln in ax.lines if (gid := ln.get_gid() or "").startswith("points:")}
            assert set().union(*marked.values()) == {(x, y) for x in xs for y in ys}
            assert marked["points:failed"] == {(xs[0], ys[1])}
            assert marked["points:start unreachable"] == {(xs[-1], ys[-1])}
            assert len(marked["points:completed"]) == n * n - 2
        legend = [t.get_text() for t in fig.legends[0].get_texts()]
        assert {"completed", "failed", "start unreachable"} <= set(legend)
