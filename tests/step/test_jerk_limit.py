"""The jerk limit keeps every joint's and the grasp's jerk (third differences of the
recorded motion, as trajectory.csv holds it); without it the same run breaks it."""

from __future__ import annotations

import csv
import dataclasses
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from dualarm_qp.errors import ConfigError
from dualarm_qp.experiments.config import load_config, parse_config
from dualarm_qp.experiments.run import run_experiment
from dualarm_qp.experiments.setup import build_experiment
from dualarm_qp.step.limits.jerk import JerkLimit, speed_bound

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "configs" / "fr3_pair.yaml"

pytest.importorskip("franky_sim")  # the FR3's description


def _jerk_ratio(csv_path: Path, exp) -> float:
    rows = list(csv.DictReader(open(csv_path)))
    dt = exp.options.dt
    worst = 0.0
    for arm, p in ((exp.task.leader, "ql"), (exp.task.follower, "qf")):
        q = np.array([[float(r[f"{p}{j + 1}"]) for j in range(arm.n)] for r in rows])
        # from rest: two samples at rest before the first
        q = np.vstack([q[:1], q[:1], q])
        jerk = np.abs(np.diff(q, n=3, axis=0)) / dt**3
        worst = max(worst, float(np.max(jerk / arm.qddd_max)))
    return worst


@pytest.mark.parametrize("on", [True, False])
def test_jerk_from_trajectory_csv(tmp_path: Path, on: bool) -> None:
    exp = build_experiment(load_config(CONFIG), str(CONFIG))
    exp = dataclasses.replace(exp, duration=1.0,
                              options=dataclasses.replace(exp.options, jerk_limits=on))
    out = run_experiment(exp, tmp_path, progress=False, plots=False)
    assert out.ok, out.summary["message"]
    ratio = _jerk_ratio(tmp_path / "trajectory.csv", exp)
    if on:
        assert ratio <= 1 + 1e-5
        assert out.summary["realised_limits"]["leader"]["jerk_ratio_max"] <= 1 + 1e-5
    else:
        assert ratio > 1.5  # the same run without the limit breaks it


def test_speed_bound_leaves_room_to_ease_off() -> None:
    J, A, v = np.array([0.01]), np.array([0.05]), np.array([1.0])
    for x_a in (0.5, 0.9, 0.97, 0.999):
        bound = speed_bound(np.array([x_a]), v, J, A)[0]
        x = min(bound, x_a + A[0])  # the acceleration box cuts it too
        d = x - x_a
        # easing the increment off at J per sample from d never passes v
        rate, inc = x, d
        while inc > 0:
            inc -= J[0]
            rate += max(inc, 0.0)
            assert rate <= v[0] + 1e-12
        if bound > x_a + A[0]:
            continue
        # and it is the largest such rate: a little more passes v
        rate, inc = x + 1e-6, d + 1e-6
        while inc > 0:
            inc -= J[0]
            rate += max(inc, 0.0)
        assert rate > v[0]


def test_a_jerk_box_that_touches_the_speed_limit_holds_through_rounding() -> None:
    # Accelerating at the most the jerk allows into the speed limit: the jerk box's low
    # end is the limit itself, up to rounding. It must not give way (any rate at all).
    dt, v, j, a = 0.01, 1.0, 200.0, 5.0
    half = j * dt * dt
    x_a = 0.99
    x_p = 2.0 * x_a - half - v
    while 2.0 * x_a - x_p - half <= v:  # part the boxes by rounding only
        x_p = np.nextafter(x_p, -np.inf)
    assert 2.0 * x_a - x_p - half - v < 1e-14
    limit = JerkLimit(np.array([j]), np.array([a]), np.array([v]), dt)
    ctx = SimpleNamespace(x_applied=np.array([x_a]), x_applied_prev=np.array([x_p]),
                          rate_lo=np.array([-np.inf]), rate_hi=np.array([np.inf]))
    box = limit.constraint(ctx)
    lower, upper = np.asarray(box.lower), np.asarray(box.upper)
    assert np.isfinite(lower).all() and np.isfinite(upper).all()
    assert lower[0] <= upper[0] <= v
    assert upper[0] == pytest.approx(v, abs=1e-12)


def test_jerk_limits_need_a_jerk_limit_for_every_joint() -> None:
    data = load_config(CONFIG).model_dump(mode="json", exclude_unset=True)
    del data["leader"]["qddd_max"]
    with pytest.raises(ConfigError, match=r"leader\.qddd_max"):
        build_experiment(parse_config(data, "x.yaml"), "x.yaml")
