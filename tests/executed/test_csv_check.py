"""The CSV checker can fail: doctored copies of a good trajectory are caught."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from csv_check import (
    check_completed_run,
    check_geometry,
    check_ranges,
    check_speeds,
    limits_of,
    read_trajectory,
    write_trajectory,
)
from executed_runs import run


@pytest.fixture(scope="module")
def good(tmp_path_factory: pytest.TempPathFactory):
    out = tmp_path_factory.mktemp("good")
    exp, summary = run("puma_beam_fast", "nullspace", out)
    assert summary["completed"], summary.get("failure")
    traj = read_trajectory(out / "trajectory.csv")
    assert check_completed_run(traj, exp) == []
    return exp, traj


def _copy(traj):
    return {k: v.copy() for k, v in traj.items()}


def _reread(traj, tmp_path: Path):
    write_trajectory(tmp_path / "doctored.csv", traj)
    return read_trajectory(tmp_path / "doctored.csv")


def test_one_speed_ten_percent_over_is_caught(good, tmp_path: Path) -> None:
    exp, traj = good
    lim = limits_of(exp)
    bad = _copy(traj)
    col, k = "qf2", len(bad["t"]) // 2
    vmax = lim.speeds[col]
    # Shift every row after k so that exactly one step, k -> k+1, runs at 1.1 v_max.
    shift = 1.1 * vmax * lim.dt - (bad[col][k + 1] - bad[col][k])
    bad[col][k + 1:] += shift
    bad = _reread(bad, tmp_path)
    problems = check_speeds(bad, lim)
    assert len(problems) == 1 and problems[0].startswith(f"speed {col}: 1 steps")
    assert f"rows {k}->{k + 1}" in problems[0] and "ratio 1.1" in problems[0]
    assert check_completed_run(bad, exp)
    # 1.1x is caught but 1 + 1e-7 is not.
    ok = _copy(traj)
    ok[col][k + 1:] += (1 + 1e-7) * vmax * lim.dt - (ok[col][k + 1] - ok[col][k])
    assert check_speeds(ok, lim) == []


def test_range_re_exit_is_caught(good) -> None:
    exp, traj = good
    lim = limits_of(exp)
    bad = _copy(traj)
    col = "ql1"
    _lo, hi = lim.bounds[col]
    k = len(bad["t"]) // 2
    bad[col][k] = hi + 1e-6          # one row just outside, the rest inside
    problems = check_ranges(bad, lim)
    assert len(problems) == 1 and problems[0].startswith(f"range {col}")
    assert f"rows {k - 1}->{k}" in problems[0]
    # The grasp starts outside [0, 0.4] m: moving it further out is caught too.
    g = _copy(traj)
    _lo, hi = lim.bounds["grasp"]
    assert g["grasp"][0] > hi
    g["grasp"][1] = g["grasp"][0] + 1e-6
    assert any(p.startswith("range grasp") for p in check_ranges(g, lim))


def test_closure_and_tracking_breaks_are_caught(good) -> None:
    exp, traj = good
    bad = _copy(traj)
    bad["qf1"][3] += 0.01            # ~10 mm at the follower's hand
    problems = check_geometry(bad, exp)
    assert len(problems) == 1 and problems[0].startswith("grasp closure: 1 rows")
    bad = _copy(traj)
    bad["path_t"][5] += 0.01         # D(path_t) moves ~3 mm away from the leader
    problems = check_geometry(bad, exp)
    assert any(p.startswith("leader tracking") for p in problems)
    assert np.isfinite(bad["path_t"]).all()


def test_a_slow_creep_outside_a_range_is_caught(good) -> None:
    """Each step 0.6e-9 further out (under the 1e-9 slack), 20 steps: 1.2e-8 in all."""
    exp, traj = good
    lim = limits_of(exp)
    bad = _copy(traj)
    col = "qf1"
    _lo, hi = lim.bounds[col]
    k = len(bad["t"]) // 2
    bad[col][k:k + 20] = hi + 0.6e-9 * np.arange(1, 21)
    assert check_ranges(bad, lim)


def test_the_library_catches_the_same_creep() -> None:
    from dualarm_qp.control.realised import measure

    x = np.concatenate([np.linspace(0.0, 1.0, 10), 1.0 + 0.6e-9 * np.arange(1, 101)])
    report = measure(x[:, None], np.array([0.0]), np.array([1.0]), np.array([np.inf]), 0.01,
                     ["q"])
    assert report.breach is not None and report.breach.criterion == "range"
    steady = np.concatenate([np.linspace(0.0, 1.0, 10), np.full(100, 1.0 + 0.5e-9)])
    assert measure(steady[:, None], np.array([0.0]), np.array([1.0]), np.array([np.inf]),
                   0.01, ["q"]).breach is None
