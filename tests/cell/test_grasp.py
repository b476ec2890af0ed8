"""The grasp estimated from both arms' joints is the grasp the rollout integrated."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from dualarm_qp.cell.grasp import estimate_grasp
from dualarm_qp.control.rollout import rollout
from dualarm_qp.experiments.config import load_config
from dualarm_qp.experiments.setup import build_experiment

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("name", ["puma_beam_limits.yaml", "curved_bar_waypoints.yaml"])
def test_estimate_recovers_the_rollouts_grasp(name: str) -> None:
    path = ROOT / "configs" / name
    exp = dataclasses.replace(build_experiment(load_config(path), str(path)), duration=1.0)
    res = rollout(exp.controller(), exp.initial, duration=exp.duration, limits=exp.limits)
    tr = res.trace
    for k in range(0, len(tr), 5):
        est = estimate_grasp(exp.task, tr.q_l[k], tr.q_f[k])
        # what is left is the closure error the rollout recorded, and the grasp is within
        # that distance of the integrated one
        assert est.closure_pos <= tr.closure_pos_err[k] + 1e-12
        assert abs(est.sigma - tr.grasp[k]) <= tr.closure_pos_err[k] + 1e-9


def test_a_hand_off_the_line_shows_as_closure_error() -> None:
    path = ROOT / "configs" / "puma_beam_limits.yaml"
    exp = build_experiment(load_config(path), str(path))
    s0 = exp.initial
    est = estimate_grasp(exp.task, s0.q_l, s0.q_f)
    assert est.sigma == pytest.approx(s0.sigma, abs=1e-9)
    q_f = s0.q_f + np.array([0.0, 0.0, 0.0, 0.0, 0.02, 0.0])  # the wrist tilts the hand
    off = estimate_grasp(exp.task, s0.q_l, q_f)
    assert off.closure_rot > 0.019
