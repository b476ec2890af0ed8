"""joints.png and rates.png: every joint in a lane of its own, scaled to its limits.

Read through the Figure objects: each lane's label (gid ``label:<column>``) sits at the
lane's middle and names the joint and its limits; the limits are dashed lines (gid
``limit:<column>``) a fixed height above and below the middle; each trace (gids
``joint:``, ``commanded:``, ``realised:``) is its joint's values scaled so that the
limits fall on those lines; the time outside a limit is shaded across the lane (gid
``outside:<column>``).
"""

from __future__ import annotations

import dataclasses
import re

import numpy as np
import pytest
from test_figures import DEG, limits_run, synthetic, synthetic_limits  # noqa: F401

from dualarm_qp.experiments.figures import DisplayUnits, PlotLimits, RunData
from dualarm_qp.experiments.figures.canvas import outside_spans
from dualarm_qp.experiments.figures.lanes import CLIP, LIMIT, joints_figure, rates_figure
from dualarm_qp.experiments.figures.rundata import ArmLimits


def label(fig, column: str):
    found = [t for ax in fig.axes for t in ax.texts if t.get_gid() == f"label:{column}"]
    assert len(found) == 1, (column, len(found))
    return found[0]


def middle(fig, column: str) -> float:
    return float(label(fig, column).get_position()[1])


def limit_heights(fig, column: str) -> list[float]:
    return sorted(float(seg[0][1]) for ax in fig.axes for c in ax.collections
                  if c.get_gid() == f"limit:{column}" for seg in c.get_segments())


def trace(fig, gid: str):
    found = [ln for ax in fig.axes for ln in ax.get_lines() if ln.get_gid() == gid]
    assert len(found) == 1, (gid, len(found))
    return found[0]


def lane_spans(fig, column: str) -> list[float]:
    """The shaded intervals of a lane, flat: ``[start0, end0, start1, ...]``."""
    out = []
    for ax in fig.axes:
        for c in ax.collections:
            if c.get_gid() == f"outside:{column}":
                out += [(float(p.vertices[:, 0].min()), float(p.vertices[:, 0].max()))
                        for p in c.get_paths()]
    return [x for pair in sorted(out) for x in pair]


def numbers(text: str) -> list[float]:
    """The numbers in a label (true minus signs, thousands separators)."""
    plain = text.replace("\N{MINUS SIGN}", "-").replace(",", "")
    return [float(v) for v in re.findall(r"-?\d+(?:\.\d+)?", plain)]


def scaled(values, lo: float, hi: float, mid: float):
    """Where a lane draws ``values``: ``lo`` on the lower line, ``hi`` on the upper."""
    y = mid + LIMIT * (2.0 * (np.asarray(values) - lo) / (hi - lo) - 1.0)
    return np.clip(y, mid - CLIP, mid + CLIP)


# --- layout -----------------------------------------------------------------------------

def test_one_axis_holds_a_lane_for_every_joint_of_both_arms():
    data, limits = synthetic(7), synthetic_limits(7)
    for fig, column in ((joints_figure(data, limits), "q{}{}"),
                        (rates_figure(data, limits), "q{}_dot{}")):
        assert len(fig.axes) == 1
        (ax,) = fig.axes
        assert not len(ax.get_yticks())  # the labels are texts, not ticks
        order = [column.format(arm, j) for arm in "lf" for j in range(1, 8)]
        heights = [middle(fig, c) for c in order]
        assert heights == sorted(heights, reverse=True)  # the leader's first, from the top
        assert np.diff(heights) == pytest.approx(-1.0)
        assert [label(fig, c).get_text().split()[0] for c in order] == [
            f"q{j}" for _ in "lf" for j in range(1, 8)]
        names = [t.get_text() for t in ax.texts if t.get_gid() is None]
        assert names == ["leader", "follower"]


def test_accelerations_get_an_axis_of_lanes_beside_the_rates():
    data = synthetic()
    arm = ArmLimits(np.full(6, -1.0), np.full(6, 1.0), np.full(6, 3.0), np.full(6, 50.0))
    limits = dataclasses.replace(synthetic_limits(), leader=arm, follower=arm,
                                 acceleration_limits_enforced=True)
    fig = rates_figure(data, limits)
    assert len(fig.axes) == 2
    rates, accelerations = fig.axes
    mid = middle(fig, "qf_ddot3")
    assert limit_heights(fig, "qf_ddot3") == pytest.approx([mid - LIMIT, mid + LIMIT])
    assert "\N{PLUS-MINUS SIGN}2,865" in label(fig, "qf_ddot3").get_text()  # 50 rad/s^2
    acc = data.realised_accelerations("f")[:, 2]
    line = trace(fig, "realised:qf_ddot3")
    assert line.axes is accelerations
    assert line.get_ydata() == pytest.approx(scaled(acc, -50.0, 50.0, mid), nan_ok=True)
    assert lane_spans(fig, "qf_ddot3")  # 200 rad/s^2 against 50
    assert trace(fig, "realised:qf_dot3").axes is rates


def test_jerk_limits_add_an_axis_of_jerk_lanes():
    data = synthetic()
    arm = ArmLimits(np.full(6, -1.0), np.full(6, 1.0), np.full(6, 3.0), np.full(6, 500.0),
                    np.full(6, 3000.0))
    plain = dataclasses.replace(synthetic_limits(), leader=arm, follower=arm)
    assert len(rates_figure(data, plain).axes) == 1  # none kept: no axis
    limits = dataclasses.replace(plain, jerk_limits_enforced=True)
    fig = rates_figure(data, limits, title="t")
    assert fig.texts[-1].get_text().endswith("(dashed); jerks against theirs")
    rates, jerks = fig.axes
    assert trace(fig, "realised:qf_dot3").axes is rates
    assert "jerk" in jerks.get_title()
    mid = middle(fig, "qf_dddot3")
    assert limit_heights(fig, "qf_dddot3") == pytest.approx([mid - LIMIT, mid + LIMIT])
    jerk = data.realised_jerks("f")[:, 2]
    line = trace(fig, "realised:qf_dddot3")
    assert line.axes is jerks
    assert line.get_ydata() == pytest.approx(scaled(jerk, -3000.0, 3000.0, mid), nan_ok=True)
    # over 3000 rad/s^3 at sample 2 (-4000) only among the first five
    assert lane_spans(fig, "qf_dddot3")[:2] == pytest.approx([0.15, 0.25])
    both = rates_figure(data, dataclasses.replace(limits, acceleration_limits_enforced=True))
    assert [ax.get_title().split()[1] for ax in both.axes[1:]] == ["accelerations", "jerks"]


# --- the experiment's limits on the lines -----------------------------------------------

def test_joint_lanes_put_each_range_on_the_lines(limits_run):  # noqa: F811
    exp, out, _ = limits_run
    data = RunData.read(out / "trajectory.csv")
    fig = joints_figure(data, PlotLimits.from_experiment(exp))
    for arm, model in (("l", exp.task.leader), ("f", exp.task.follower)):
        q = data.joints(arm)
        for j in range(model.n):
            column = f"q{arm}{j + 1}"
            mid = middle(fig, column)
            lo, hi = model.q_min[j] * DEG, model.q_max[j] * DEG
            assert limit_heights(fig, column) == pytest.approx([mid - LIMIT, mid + LIMIT])
            assert trace(fig, f"joint:{column}").get_ydata() == pytest.approx(
                scaled(q[:, j] * DEG, lo, hi, mid))
            text = label(fig, column).get_text()
            assert text.startswith(f"q{j + 1} ")
            stated = numbers(text)[1:3]
            if "\N{PLUS-MINUS SIGN}" in text:  # a range symmetric about 0
                stated = [-stated[0], stated[0]]
            assert stated == pytest.approx([lo, hi], rel=1e-3)  # four digits


def test_rate_lanes_put_each_speed_limit_on_the_lines(limits_run):  # noqa: F811
    exp, out, _ = limits_run
    data = RunData.read(out / "trajectory.csv")
    fig = rates_figure(data, PlotLimits.from_experiment(exp))
    for arm, model in (("l", exp.task.leader), ("f", exp.task.follower)):
        commanded, realised = data.commanded_rates(arm), data.realised_rates(arm)
        for j in range(model.n):
            column = f"q{arm}_dot{j + 1}"
            mid, v = middle(fig, column), model.qd_max[j] * DEG
            assert limit_heights(fig, column) == pytest.approx([mid - LIMIT, mid + LIMIT])
            assert numbers(label(fig, column).get_text())[1] == pytest.approx(v, rel=1e-3)
            assert trace(fig, f"commanded:{column}").get_ydata() == pytest.approx(
                scaled(commanded[:-1, j] * DEG, -v, v, mid))  # the last, never applied: out
            assert trace(fig, f"realised:{column}").get_ydata() == pytest.approx(
                scaled(realised[:, j] * DEG, -v, v, mid), nan_ok=True)


def test_the_follower_starts_outside_and_its_lane_says_so(limits_run):  # noqa: F811
    """Table 2 starts q1 outside its range: its lane is shaded from t = 0."""
    exp, out, _ = limits_run
    data = RunData.read(out / "trajectory.csv")
    fig = joints_figure(data, PlotLimits.from_experiment(exp))
    shaded = lane_spans(fig, "qf1")
    assert shaded and shaded[0] == pytest.approx(0.0)
    assert lane_spans(fig, "ql1") == []


# --- outside the limits -----------------------------------------------------------------

def test_shading_spans_exactly_the_samples_outside_and_far_values_are_clipped():
    data, limits = synthetic(), synthetic_limits()  # qf3: 2 rad against a +-1 rad range
    joints = joints_figure(data, limits)
    assert lane_spans(joints, "qf3") == pytest.approx([0.15, 0.45, 0.85, 0.9])
    assert lane_spans(joints, "qf2") == []
    mid = middle(joints, "qf3")
    y = trace(joints, "joint:qf3").get_ydata()
    assert y.max() == pytest.approx(mid + CLIP)  # in its own lane: clipped at its edge
    assert label(joints, "qf3").get_text() == ("q3 \N{PLUS-MINUS SIGN}57.3\nreaches 115")
    assert label(joints, "qf2").get_text() == "q2 \N{PLUS-MINUS SIGN}57.3"  # none clipped
    rates = rates_figure(data, limits)
    # the realised rate (20 rad/s) is over the 3 rad/s limit at samples 1 and 4 (and 8)
    assert lane_spans(rates, "qf_dot3") == pytest.approx([0.05, 0.15, 0.35, 0.45,
                                                          0.75, 0.85])
    assert data.realised_rates("f")[1, 2] == pytest.approx(20.0)
    text = label(rates, "qf_dot3").get_text()  # +-20 rad/s, clipped: the label says so
    assert "\nreaches " in text and abs(numbers(text)[-1]) == pytest.approx(1150.0)


def test_a_side_without_a_limit_has_no_line_and_the_label_says_so():
    data = synthetic()
    lo, hi, speed = np.full(6, -1.0), np.full(6, 1.0), np.full(6, 3.0)
    lo[1], hi[1] = -np.inf, np.inf  # q2: a continuous joint
    hi[3] = np.inf  # q4: a lower limit only
    speed[4] = np.inf  # q5: no speed limit
    arm = ArmLimits(lo, hi, speed)
    data.columns["qf_dot5"] = np.linspace(-0.5, 1.0, 10)
    limits = dataclasses.replace(synthetic_limits(), leader=arm, follower=arm)
    joints = joints_figure(data, limits)
    assert limit_heights(joints, "qf2") == []
    assert label(joints, "qf2").get_text() == "q2 no range"
    mid = middle(joints, "qf4")
    assert limit_heights(joints, "qf4") == pytest.approx([mid - LIMIT])
    assert label(joints, "qf4").get_text() == "q4 >= \N{MINUS SIGN}57.3"
    rates = rates_figure(data, limits)
    assert limit_heights(rates, "qf_dot5") == []
    # scaled to the largest commanded rate applied, 0.833 rad/s (the last row's is not)
    assert label(rates, "qf_dot5").get_text() == ("q5 no limit\nscaled to "
                                                  "\N{PLUS-MINUS SIGN}47.7")
    mid = middle(rates, "qf_dot5")
    assert trace(rates, "commanded:qf_dot5").get_ydata().max() == pytest.approx(mid + LIMIT)
    assert lane_spans(rates, "qf_dot5") == []


def test_lanes_show_the_files_units():
    data = synthetic()
    for units, per_rad in ((DisplayUnits("deg", "mm"), DEG), (DisplayUnits("rad", "m"), 1.0)):
        limits = dataclasses.replace(synthetic_limits(), units=units)
        joints, rates = joints_figure(data, limits, "t"), rates_figure(data, limits, "t")
        assert f"[{units.angle}]" in joints.get_suptitle()
        assert f"[{units.angle}/s]" in rates.get_suptitle()
        assert numbers(label(joints, "qf3").get_text())[1] == pytest.approx(per_rad, rel=1e-3)
        assert numbers(label(rates, "qf_dot3").get_text())[1] == pytest.approx(3 * per_rad,
                                                                              rel=1e-3)
        # the lanes are the same whatever the unit: each value against its own limits
        mid = middle(joints, "qf3")
        assert trace(joints, "joint:qf3").get_ydata() == pytest.approx(
            scaled(data.col("qf3") * per_rad, -per_rad, per_rad, mid))


def test_outside_spans_of_a_lane_match_the_canvas_rule():
    """The lanes shade with the same rule as every other figure (one sample: a band)."""
    data, limits = synthetic(), synthetic_limits()
    fig = joints_figure(data, limits)
    q = data.col("qf3")
    expected = outside_spans(data.t, np.abs(q) > 1.0 + 1e-9)
    assert lane_spans(fig, "qf3") == pytest.approx([x for pair in expected for x in pair])
