"""Figures of a run, of the reproduction and of the bench, and the run's report.html.

The figures are checked through the matplotlib Figure objects the drawing functions
return: limit lines (gid ``limit:<name>``) sit at the limits, shaded spans (gid
``outside:<name>``) cover exactly the samples outside, speed axes turn logarithmic only
beyond their limit.
"""

from __future__ import annotations

import dataclasses
import json
import re
from pathlib import Path

import numpy as np
import pytest
import yaml

from dualarm_qp.errors import InvalidInputError
from dualarm_qp.experiments import build_experiment, load_config
from dualarm_qp.experiments.figures import (
    RUN_FIGURES,
    Curve,
    DisplayUnits,
    PlotLimits,
    RunData,
    closure_figure,
    comparison_figure,
    grasp_figure,
    joints_figure,
    rates_figure,
    tracking_figure,
)
from dualarm_qp.experiments.figures.canvas import outside_spans
from dualarm_qp.experiments.figures.compare import range_label
from dualarm_qp.experiments.figures.rundata import ArmLimits
from dualarm_qp.experiments.html_report import (
    CRITERION_TEXT,
    render_run_report,
    write_run_report,
)
from dualarm_qp.experiments.run import run_experiment

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
DEG = 180.0 / np.pi


def short_limits_experiment(tmp_path: Path, duration: float = 0.31):
    d = yaml.safe_load((CONFIGS / "puma_beam_limits.yaml").read_text())
    d["controller"]["duration"] = duration  # 11 samples
    path = tmp_path / "short.yaml"
    path.write_text(yaml.safe_dump(d))
    return build_experiment(load_config(path), str(path))


@pytest.fixture(scope="module")
def limits_run(tmp_path_factory):
    """A short run of the beam with speed limits, written with its figures."""
    tmp = tmp_path_factory.mktemp("run")
    exp = short_limits_experiment(tmp)
    out = tmp / "out"
    outcome = run_experiment(exp, out, progress=False)
    return exp, out, outcome


def lines(fig, gid: str) -> list:
    return [ln for ax in fig.axes for ln in ax.get_lines() if ln.get_gid() == gid]


def line_levels(fig, gid: str) -> list[float]:
    return sorted(float(ln.get_ydata()[0]) for ln in lines(fig, gid))


def axis_levels(ax, gid: str) -> list[float]:
    return sorted(float(ln.get_ydata()[0]) for ln in ax.get_lines() if ln.get_gid() == gid)


def spans(ax, gid: str) -> list[float]:
    """The shaded intervals of ``gid`` on ``ax``, flat: ``[start0, end0, start1, ...]``."""
    out = []
    for p in ax.patches:
        if p.get_gid() != gid:
            continue
        if hasattr(p, "get_width"):
            out.append((float(p.get_x()), float(p.get_x() + p.get_width())))
        else:  # older matplotlib: a Polygon
            xs = np.asarray(p.get_xy())[:, 0]
            out.append((float(xs.min()), float(xs.max())))
    return [x for pair in sorted(out) for x in pair]


def flat(pairs) -> list[float]:
    return [x for pair in pairs for x in pair]


def synthetic(n_joints: int = 6, *, leader_grasp: bool = False) -> RunData:
    """Ten samples, 0.1 s apart, with known excursions."""
    t = np.arange(10) * 0.1
    cols: dict = {"t": t}
    for arm in ("l", "f"):
        for j in range(n_joints):
            cols[f"q{arm}{j + 1}"] = np.zeros(10)
            cols[f"q{arm}_dot{j + 1}"] = np.zeros(10)
    cols["qf3"] = np.array([0, 0, 2.0, 2.0, 2.0, 0, 0, 0, 0, 2.0])  # range +-1 rad
    cols["grasp"] = np.array([0.45, 0.41, 0.39, 0.2, 0.2, 0.2, 0.5, 0.5, 0.2, 0.2])
    cols["m"] = np.concatenate(([-8.3], np.full(9, -0.01)))
    cols["scale"] = np.array([1, 1, 0.5, 1, 1, 1, 1, 1, 1, 0.0])
    cols["sigma_min_l"] = np.full(10, 0.1)
    cols["sigma_min_f"] = np.array([0.1, 0.1, 1e-4, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1])
    for name in ("leader_pos_err", "leader_rot_err", "closure_pos_err", "closure_rot_err"):
        cols[name] = np.full(10, 1e-9)
    if leader_grasp:
        cols["grasp_leader"] = np.linspace(0.0, 0.09, 10)
        cols["m_leader"] = np.full(10, 0.1)
    cols["status"] = np.array(["optimal"] * 10)
    return RunData(cols)


def synthetic_limits(n_joints: int = 6, *, leader_grasp_range=None) -> PlotLimits:
    arm = ArmLimits(np.full(n_joints, -1.0), np.full(n_joints, 1.0), np.arange(1, n_joints + 1)
                    * 1.0)
    return PlotLimits(leader=arm, follower=arm, grasp_range=(0.0, 0.4), grasp_speed_max=0.1,
                      speed_limits_enforced=True, closure=(1e-3, 1e-2), tracking=(1e-3, 1e-2),
                      singular_value_min=1e-3, leader_grasp_range=leader_grasp_range)


# --- a run's outputs --------------------------------------------------------------------

def test_a_run_writes_its_figures_and_lists_them(limits_run):
    _, out, outcome = limits_run
    for name in (*RUN_FIGURES, "report.html"):
        assert (out / name).stat().st_size > 1000, name
    listed = json.loads((out / "summary.json").read_text())["outputs"]
    mine = ["trajectory.csv", *RUN_FIGURES, "report.html"]
    assert [f for f in listed if f in mine] == mine  # in the order they are written
    assert sorted(listed) == sorted(p.name for p in out.iterdir() if p.name != "summary.json")
    assert outcome.summary["outputs"] == listed


def test_the_report_is_self_contained(limits_run):
    _, out, _ = limits_run
    page = (out / "report.html").read_text()
    assert page.count('src="data:image/png;base64,') == len(RUN_FIGURES)
    refs = re.findall(r"""(?:src|href)\s*=\s*["']?([^"'\s>]+)""", page, flags=re.I)
    assert refs, "no reference found at all: the pattern is wrong"
    external = [r for r in refs if re.match(r"(https?:)?//", r, flags=re.I)]
    assert not external, external
    assert "<script" not in page.lower() and "@import" not in page
    assert "animation.html" not in page  # none in the folder
    assert "clearance.png" not in page and 'id="clearance"' not in page  # no collision scene
    summary = json.loads((out / "summary.json").read_text())
    assert summary["experiment"] in page and summary["status"] in page


def test_the_report_leads_with_the_verdict_and_folds_the_raw_values(limits_run):
    _, out, _ = limits_run
    page = (out / "report.html").read_text()
    verdict = page.index('id="verdict"')
    details = page.index('<details id="all-values">')
    assert verdict < page.index("<table") < page.index("<figure") < details
    assert "<strong>Completed</strong>: the whole path D(t)" in page[verdict:]
    glance = page[verdict:page.index("<figure")]
    assert "100% of D(t)" in glance and "time lost to slowing</th><td>none" in glance
    # the worst share of each limit, with its joint; the follower starts outside (Table 2)
    limits = glance[glance.index('<table class="limits">'):]
    row = limits[limits.index("follower arm"):]
    row = row[:row.index("</tr>")]
    assert '<td class="over">103%</td><td>qf1; started outside, at 103%</td>' in row
    assert "leader arm" in limits and "follower grasp" in limits
    # every raw key is still there, folded below
    assert "margin_qf_min_after_start_rad" in page[details:]
    assert "margin_qf_min_after_start_rad" not in page[:details]


def test_a_failed_run_says_first_why(limits_run, tmp_path):
    _, out, _ = limits_run
    summary = json.loads((out / "summary.json").read_text())
    message = "path not completed: 64.9% of the path in 0.93 s (the duration cap)"
    summary.update(status="failed", completed=False, message=message,
                   path_completed_pct=64.9, time_lost_to_scaling_s=0.527,
                   failure={"criterion": "path_incomplete", "sample": 30, "t_s": 0.93,
                            "amount": 0.649, "limit": 1.0, "message": message})
    page = render_run_report(tmp_path, summary, [])
    verdict = page[page.index('id="verdict"'):]
    verdict = verdict[:verdict.index("</p>")]
    assert "<strong>FAILED</strong> on <code>path_incomplete</code>" in verdict
    assert CRITERION_TEXT["path_incomplete"] in verdict and message in verdict
    assert "64.9% of D(t)" in page and "0.527 s (the limits slowed the path" in page


def test_the_report_shows_an_animation_beside_it(limits_run, tmp_path):
    _, out, _ = limits_run
    folder = tmp_path / "copy"
    folder.mkdir()
    for p in out.iterdir():
        (folder / p.name).write_bytes(p.read_bytes())
    (folder / "animation.html").write_text("<html></html>")
    assert write_run_report(folder) == "report.html"  # from summary.json, as after a run
    page = (folder / "report.html").read_text()
    assert '<iframe src="animation.html"' in page and 'href="animation.html"' in page
    assert page.count("data:image/png;base64,") == len(RUN_FIGURES)


def test_no_plots_means_no_figures_and_no_report(tmp_path):
    exp = short_limits_experiment(tmp_path, duration=0.062)
    outcome = run_experiment(exp, tmp_path / "o", progress=False, plots=False)
    written = {p.name for p in (tmp_path / "o").iterdir()}
    assert not written & {*RUN_FIGURES, "report.html"}
    assert "report.html" not in outcome.summary["outputs"]


# --- limit lines at the limits ----------------------------------------------------------

def test_run_figures_draw_the_experiments_limits(limits_run):
    exp, out, _ = limits_run
    data = RunData.read(out / "trajectory.csv")
    limits = PlotLimits.from_experiment(exp)
    # the joints' and rates' limits: tests/experiments/test_lanes.py
    grasp = grasp_figure(data, limits)
    surface = exp.task.surface
    assert line_levels(grasp, "limit:grasp") == pytest.approx(
        [surface.sigma_min * 1e3, surface.sigma_max * 1e3])
    assert exp.options.grasp_speed_max == pytest.approx(0.1)
    assert line_levels(grasp, "limit:grasp_speed") == pytest.approx([-100.0, 100.0])
    tracking = tracking_figure(data, limits)
    assert line_levels(tracking, "limit:singular_value_min") == pytest.approx(
        [exp.limits.singular_value_min])
    assert line_levels(tracking, "limit:tracking_pos") == pytest.approx(
        [exp.limits.tracking[0]])


def test_the_follower_starts_outside_and_the_figures_say_so(limits_run):
    """Table 2 starts the grasp (and q1: test_lanes.py) outside its range: shaded."""
    exp, out, _ = limits_run
    data = RunData.read(out / "trajectory.csv")
    limits = PlotLimits.from_experiment(exp)
    grasp = data.col("grasp")
    expected = outside_spans(data.t, (grasp > exp.task.surface.sigma_max + 1e-9))
    ax_g = grasp_figure(data, limits).axes[0]
    assert spans(ax_g, "outside:grasp") == pytest.approx(flat(expected))
    assert expected  # 11 samples of 31 ms: the grasp is still sliding back at 100 mm/s


# --- shading and axes on known data -----------------------------------------------------

def test_shading_spans_exactly_the_samples_outside():
    data, limits = synthetic(), synthetic_limits()
    ax_g = grasp_figure(data, limits).axes[0]
    # grasp outside [0, 0.4] m at samples 0-1 and 6-7, sampled every 0.1 s
    assert spans(ax_g, "outside:grasp") == pytest.approx(flat([(0.0, 0.15), (0.55, 0.75)]))
    tracking = tracking_figure(data, limits)
    assert spans(tracking.axes[1], "outside:singular_value_min") == pytest.approx(
        [0.15, 0.25])
    # the last row's scale (0: its command is never applied) is not shaded
    assert spans(tracking.axes[2], "outside:scale") == pytest.approx(flat([(0.15, 0.25)]))


def test_realised_rates_are_finite_differences():
    data = synthetic()
    real = data.realised_rates("f")
    assert real[1, 2] == pytest.approx((2.0 - 0.0) / 0.1)
    assert real[4, 2] == pytest.approx(-20.0)
    assert np.isnan(real[-1]).all()
def test_realised_jerks_are_third_differences():
    data = synthetic()
    jerk = data.realised_jerks("f")
    # qf3: 0, 0, 2, 2, 2, 0 rad at 0.1 s: rates 0, 20, 0, 0, -20; accelerations 0, 200,
    # -200, 0, -200; jerks their differences over 0.1 s (their lanes: test_lanes.py)
    assert jerk[:5, 2] == pytest.approx([0.0, 2000.0, -4000.0, 2000.0, -2000.0])
    assert np.isnan(jerk[-1]).all()


def test_a_speed_axis_is_logarithmic_only_beyond_its_limit():
    data, limits = synthetic(), synthetic_limits()
    ax = grasp_figure(data, limits).axes[1]
    assert ax.get_yscale() == "symlog"  # the -8.3 m/s first sample: 83 times the limit
    assert ax.get_yscale() == "symlog" and ax.yaxis.get_transform().linthresh == 100.0
    low, high = ax.get_ylim()
    assert low < -8300 and high > 8300
    calm = synthetic()
    calm.columns["m"] = np.full(10, -0.05)
    calm.columns["grasp"] = np.full(10, 0.2)
    ax = grasp_figure(calm, limits).axes[1]
    assert ax.get_yscale() == "linear"
    assert ax.get_ylim() == pytest.approx((-115.0, 115.0))


def test_error_axes_stop_where_the_tolerances_stop_mattering():
    """Six decades below the smallest tolerance (1 mm: 1e-9), not at 1e-16; what is
    smaller (the exact start, rounding) lies on the bottom edge and the legend says so."""
    data, limits = synthetic(), synthetic_limits()
    data.columns["leader_pos_err"] = np.concatenate(([0.0, 2e-16], np.full(8, 3e-6)))
    data.columns["closure_rot_err"] = np.full(10, 1e-12)
    tracking = tracking_figure(data, limits)
    closure = closure_figure(data, limits)
    for ax in (tracking.axes[0], closure.axes[0]):
        assert ax.get_yscale() == "log"
        assert ax.get_ylim() == pytest.approx((1e-9, 1e-1))  # tolerances 1e-3 m, 1e-2 rad
        assert min(np.min(ln.get_ydata()) for ln in ax.get_lines() if len(ln.get_ydata())
                   ) >= 1e-9
        assert "below 1e-9: on the bottom edge" in ax.get_legend_handles_labels()[1]
    position = next(ln for ln in tracking.axes[0].get_lines()
                    if ln.get_label() == "position [m]")
    assert list(position.get_ydata()[:3]) == pytest.approx([1e-9, 1e-9, 3e-6])
    # singular values: two decades below the threshold (1e-3)
    assert tracking.axes[1].get_ylim() == pytest.approx((1e-5, 1.0))
    calm = synthetic()  # every error 1e-9: nothing below the axis, no note
    labels = closure_figure(calm, limits).axes[0].get_legend_handles_labels()[1]
    assert not any("bottom edge" in lab for lab in labels)


def test_joint_counts_come_from_the_header_and_a_sliding_leader_grasp_is_drawn():
    data = synthetic(7, leader_grasp=True)
    assert data.n_joints("l") == data.n_joints("f") == 7  # 14 lanes: test_lanes.py
    limits = synthetic_limits(7, leader_grasp_range=(0.0, 0.05))
    grasp = grasp_figure(data, limits)
    labels = [ln.get_label() for ln in grasp.axes[0].get_lines()]
    assert "leader grasp" in labels
    assert line_levels(grasp, "limit:grasp_leader") == pytest.approx([0.0, 50.0])
    assert spans(grasp.axes[0], "outside:grasp_leader") == pytest.approx(flat([(0.55, 0.9)]))


def test_a_runs_figures_avoid_the_costly_ways_to_draw(monkeypatch):
    """What made the plots cost several times the run: tight_layout (it measures every
    tick label before placing the axes), mathematical typesetting of the log axes'
    labels (parsed anew for each), minor ticks on axes spanning many decades, and the
    alpha channel of an opaque image."""
    import io

    import matplotlib.mathtext
    from matplotlib.figure import Figure
    from PIL import Image

    from dualarm_qp.experiments.figures.canvas import png_bytes

    calls = {"tight_layout": 0, "mathtext": 0}

    def counted(name, original):
        def call(*args, **kwargs):
            calls[name] += 1
            return original(*args, **kwargs)
        return call

    monkeypatch.setattr(Figure, "tight_layout", counted("tight_layout", Figure.tight_layout))
    monkeypatch.setattr(matplotlib.mathtext.MathTextParser, "parse",
                        counted("mathtext", matplotlib.mathtext.MathTextParser.parse))
    data, limits = synthetic(), synthetic_limits()
    log_axes = 0
    for draw in (grasp_figure, tracking_figure, closure_figure):  # they had tight_layout
        fig = draw(data, limits, "title")
        if draw is not grasp_figure:  # drawn: the log axes' labels are typeset
            assert Image.open(io.BytesIO(png_bytes(fig))).mode == "P"  # a palette
        for ax in fig.axes:
            if ax.get_yscale() == "log":
                log_axes += 1
                assert not len(ax.yaxis.get_minorticklocs())
                labels = [t.get_text() for t in ax.get_yticklabels()]
                assert "10\N{SUPERSCRIPT MINUS}\N{SUPERSCRIPT THREE}" in labels, labels
    assert log_axes == 3  # tracking: error, singular values; closure
    assert calls == {"tight_layout": 0, "mathtext": 0}


@pytest.mark.slow
def test_a_runs_figures_make_few_ticks():
    """What was left of the cost: the 14 (28) panels of joints.png and rates.png, each an
    axis of its own, and the ticks (several artists each) of every axis: now one axis of
    lanes (test_lanes.py), at most six ticks an axis (a speed axis beyond its limit has
    its own round ticks), none beyond its ends, and a column of axes sharing its time
    axis ticks the bottom one only."""
    from dualarm_qp.experiments.figures.canvas import TICKS, png_bytes

    data, limits = synthetic(7), synthetic_limits(7)
    for draw in (joints_figure, rates_figure, grasp_figure, tracking_figure, closure_figure):
        fig = draw(data, limits, "title")
        png_bytes(fig)  # drawn: the ticks are made
        axes = fig.axes
        assert len(axes) <= 3
        for k, ax in enumerate(axes):
            for axis in (ax.xaxis, ax.yaxis):
                lo, hi = sorted(axis.get_view_interval())
                locs = axis.get_majorticklocs()
                if axis.get_scale() != "symlog":  # a speed axis's round ticks: its own
                    assert len(locs) <= TICKS + 1, (draw.__name__, k, locs)
                assert all(lo - 1e-9 * (hi - lo) <= v <= hi + 1e-9 * (hi - lo)
                           for v in locs), (draw.__name__, k, locs, lo, hi)
            shares_below = k + 1 < len(axes) and ax.get_shared_x_axes().joined(ax, axes[-1])
            assert ax.xaxis.get_visible() is not shares_below


def test_reading_a_file_that_is_not_a_trajectory_fails(tmp_path):
    bad = tmp_path / "x.csv"
    bad.write_text("a,b\n1,2\n")
    with pytest.raises(InvalidInputError, match="not a trajectory"):
        RunData.read(bad)
    bad.write_text("t,a\n0,1\n0.1\n")
    with pytest.raises(InvalidInputError, match="row 3"):
        RunData.read(bad)


def test_reading_keeps_the_nearest_pair_as_text(tmp_path):
    path = tmp_path / "trajectory.csv"
    path.write_text("t,clearance_arm_arm,clearance_pair\n"
                    "0,0.25,leader.link5 - follower.link5\n0.01,inf,\n")
    data = RunData.read(path)
    assert data.columns["clearance_pair"].tolist() == ["leader.link5 - follower.link5", ""]
    assert data.columns["clearance_arm_arm"].tolist() == [0.25, np.inf]


# --- the reproduction's comparison figures ----------------------------------------------

def test_comparison_figure_zooms_shades_and_draws_both_limits():
    t = np.arange(120) * 0.031
    jump = np.concatenate(([0.45], np.full(119, 0.19)))  # one-sample jump, like case (b)
    slide = np.maximum(0.45 - 0.1 * t, 0.1)  # 100 mm/s, like case (d)
    fig = comparison_figure(
        [Curve("(b)", t, jump, "C1"), Curve("(d)", t, slide, "C4")],
        value_range=(0.0, 0.4), speed_limit=0.1, scale=1e3, value_label="grasp [mm]",
        speed_label="speed [mm/s]", title="Fig. 6", zoom=0.5)
    (full, zoom), (speed, _) = np.reshape(fig.axes, (2, 2))
    assert zoom.get_xlim() == pytest.approx((-0.0155, 0.5))
    assert axis_levels(full, "limit:range") == pytest.approx([0, 400])
    assert axis_levels(zoom, "limit:range") == pytest.approx([400])  # 0 mm: far below
    assert line_levels(fig, "limit:speed") == pytest.approx([-100, -100, 100, 100])
    assert spans(full, "outside:range:(b)") == pytest.approx(flat([(0.0, 0.0155)]))
    outside_d = slide > 0.4 + 1e-9
    assert spans(full, "outside:range:(d)") == pytest.approx(flat(outside_spans(t, outside_d)))
    # (b)'s realised speed, 260 mm over 31 ms, is over the limit in its first sample only
    assert spans(speed, "outside:speed:(b)") == pytest.approx(flat([(0.0, 0.0155)]))
    assert spans(speed, "outside:speed:(d)") == []
    assert speed.get_yscale() == "symlog"


def test_a_range_limit_far_from_the_data_is_named_not_drawn():
    t = np.arange(5) * 0.1
    fig = comparison_figure([Curve("(a)", t, np.radians([-31, -40, -50, -40, -31]), "C0")],
                            value_range=(np.radians(-45), np.radians(225)),
                            speed_limit=None, scale=DEG, value_label="q3 [deg]",
                            speed_label="[deg/s]", title="Fig. 5", unit="deg")
    assert line_levels(fig, "limit:range") == pytest.approx([-45, -45])
    assert legend_texts(fig) == ["(a)", "range limit \N{MINUS SIGN}45 deg (the upper limit, "
                                 "225 deg, is far above the axis)"]
    assert spans(fig.axes[0], "outside:range:(a)") == pytest.approx(flat([(0.15, 0.25)]))


def test_range_legends_say_which_limits_are_drawn_and_where_the_others_are():
    assert range_label([0.0, 400.0], [], "mm") == "range limits 0 and 400 mm"
    assert range_label([400.0], [("lower", 0.0, "below")], "mm") == (
        "range limit 400 mm (the lower limit, 0 mm, is far below the axis)")
    assert range_label([], [("lower", -45.0, "below"), ("upper", 225.0, "above")],
                       "deg") == ("range limits off the axis: the lower limit, \N{MINUS SIGN}45 "
                                  "deg, is far below the axis; the upper limit, 225 deg, is "
                                  "far above the axis")


# --- readable ticks in the file's units ---------------------------------------------

def legend_texts(fig) -> list[str]:
    return [t.get_text() for leg in fig.legends for t in leg.get_texts()]


def shown_tick_labels(fig, ax) -> list[tuple[float, str]]:
    """(value, label) of the y ticks inside the axis's view, as drawn."""
    fig.canvas.draw()
    lo, hi = ax.get_ylim()
    return [(float(v), lab.get_text()) for v, lab in zip(ax.get_yticks(),
                                                         ax.get_yticklabels(), strict=True)
            if lo <= v <= hi]


def assert_readable(label: str, value: float) -> None:
    """A label a person reads: a plain number (no exponent) of at most two significant
    digits (not ``57.3`` or ``114.6``), the tick's value."""
    text = label.replace("\N{MINUS SIGN}", "-").replace(",", "")
    assert re.fullmatch(r"-?\d+(\.\d+)?", text), label
    assert float(text) == pytest.approx(value), (label, value)
    digits = text.lstrip("-").replace(".", "").strip("0")
    assert len(digits) <= 2, label


def test_speed_ticks_are_round_numbers_in_the_display_unit():
    """Fig. 5's rate axis: 1,000 deg/s jumps against a 114.6 deg/s (2 rad/s) limit."""
    t = np.arange(40) * 0.031
    q3 = np.radians(np.concatenate(([-31.0], np.linspace(-0.5, 6.0, 39))))  # a 30 deg jump
    fig = comparison_figure([Curve("(b)", t, q3, "C1")], value_range=(np.radians(-45),
                            np.radians(225)), speed_limit=2.0, scale=DEG, unit="deg",
                            value_label="q3 [deg]", speed_label="q3 rate [deg/s]",
                            title="Fig. 5")
    speed = fig.axes[2]
    assert speed.get_yscale() == "symlog"
    ticks = shown_tick_labels(fig, speed)
    for value, label in ticks:
        assert_readable(label, value)
    values = [v for v, _ in ticks]
    assert {-1000.0, -100.0, -50.0, 0.0, 50.0, 100.0, 1000.0} <= set(values)
    assert not any(np.isclose(abs(v), 2 * DEG) for v in values)  # the limit is the line
    assert "speed limit \N{PLUS-MINUS SIGN}114.6 deg/s" in legend_texts(fig)


@pytest.mark.slow
def test_run_figures_show_the_files_units():
    data = synthetic()
    for units, per_m in ((DisplayUnits("deg", "mm"), 1e3), (DisplayUnits("rad", "m"), 1.0)):
        limits = dataclasses.replace(synthetic_limits(), units=units)  # joints: test_lanes
        grasp = grasp_figure(data, limits)
        assert grasp.axes[0].get_ylabel() == f"grasp [{units.length}]"
        assert grasp.axes[1].get_ylabel() == f"sliding speed [{units.length}/s]"
        assert line_levels(grasp, "limit:grasp") == pytest.approx([0.0, 0.4 * per_m])
        for value, label in shown_tick_labels(grasp, grasp.axes[1]):
            assert_readable(label, value)


def test_the_display_units_are_the_experiment_files(tmp_path):
    d = yaml.safe_load((CONFIGS / "puma_beam_limits.yaml").read_text())
    assert DisplayUnits.of_file(CONFIGS / "puma_beam_limits.yaml") == DisplayUnits("deg", "mm")
    d["units"] = {"length": "m", "angle": "rad", "time": "s"}  # a schema check only
    path = tmp_path / "si.yaml"
    path.write_text(yaml.safe_dump(d))
    assert DisplayUnits.of_file(path) == DisplayUnits("rad", "m")
    assert DisplayUnits.of_file("<built in code>") == DisplayUnits("deg", "mm")
    with pytest.raises(InvalidInputError, match="display units"):
        DisplayUnits("grad", "mm")


# --- the bench figure -------------------------------------------------------------------

@pytest.mark.slow
def test_bench_figure_has_a_log_time_axis_and_success_and_accuracy(tmp_path):
    from dualarm_qp.bench.figure import bench_figure
    from dualarm_qp.bench.report import plot

    rows = [{"experiment": cfg, "solver": s, "success_rate": rate,
             "step_time_median_s": 1e-4, "step_time_p99_s": p99,
             "solve_time_median_s": 5e-5, "bound_violation_max": 0.0,
             "eq_residual_max": 1e-15, "closure_pos_err_max_m": 1e-5}
            for cfg in ("beam", "bar") for s, rate, p99 in (("nullspace", 1.0, 1.3e-2),
                                                              ("reference", 0.9, 2e-4))]
    fig = bench_figure(rows)
    assert len(fig.axes) == 6
    time_ax, success_ax, accuracy_ax = fig.axes[:3]
    assert time_ax.get_xscale() == "log" and accuracy_ax.get_xscale() == "log"
    medians = [ln for ln in time_ax.get_lines() if ln.get_label() == "step median"]
    assert list(medians[0].get_xdata()) == pytest.approx([100.0, 100.0])
    widths = sorted(p.get_width() for p in success_ax.patches)
    assert widths == pytest.approx([0.9, 1.0])
    plot(tmp_path / "bench.png", rows)
    assert (tmp_path / "bench.png").stat().st_size > 1000
