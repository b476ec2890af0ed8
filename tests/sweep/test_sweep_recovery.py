"""The realised limits after the start-up recovery: from the first sample inside every range."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from dualarm_qp.sweep.recovery import after_recovery

DT = 0.1


def _run(grasp: list[float]):
    """A one-joint leader and follower at rest mid-range, and the grasp given [m]."""
    n = len(grasp)
    arm = SimpleNamespace(q_min=np.array([-1.0]), q_max=np.array([1.0]),
                          qd_max=np.array([2.0]))
    task = SimpleNamespace(leader=arm, follower=arm, leader_surface=None,
                           surface=SimpleNamespace(sigma_min=0.0, sigma_max=0.4))
    g = np.array(grasp)
    trace = SimpleNamespace(
        t=np.arange(n) * DT, q_l=np.zeros((n, 1)), q_f=np.full((n, 1), 0.5),
        grasp=g, margin_ql=np.ones((n, 1)), margin_qf=np.full((n, 1), 0.5),
        margin_grasp=np.minimum(g - 0.0, 0.4 - g), margin_grasp_leader=np.full(n, np.nan),
        grasp_leader=np.full(n, np.nan))
    return after_recovery(trace, task, 0.1, DT)


def test_a_run_that_starts_outside_is_measured_from_its_first_sample_inside():
    out = _run([0.45, 0.44, 0.43, 0.42, 0.41, 0.40, 0.395, 0.39])
    assert out["recovered_at_s"] == pytest.approx(5 * DT)
    # From 0.40 on: the range ratio is |0.40 - 0.2| / 0.2 = 1, the sliding speed at most
    # 0.005 / 0.1 = 0.05 m/s of 0.1; the whole run's ratio would be 1.25 (its start).
    assert out["worst_limit_ratio_after_recovery"] == pytest.approx(1.0)
    assert out["joint_margin_min_after_recovery_rad"] == pytest.approx(0.5)


def test_a_run_that_starts_inside_counts_from_zero():
    out = _run([0.30, 0.295, 0.29])
    assert out["recovered_at_s"] == 0.0
    # grasp range 0.1 / 0.2, sliding 0.05 of 0.1 m/s, follower joint 0.5 of 1: all 0.5
    assert out["worst_limit_ratio_after_recovery"] == pytest.approx(0.5)


def test_a_run_that_never_gets_inside_has_no_numbers():
    out = _run([0.45, 0.44, 0.43])
    assert all(math.isnan(v) for v in out.values())
