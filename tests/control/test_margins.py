"""The recorded margins: one pass over the run, equal to the per-sample rule.

The rollout records the realised state each sample and writes every margin to the
ranges once, after the run (:func:`record_margins`). The grasp's margin
(:func:`grasp_margins`, vectorised over the samples, with :meth:`GraspSurface.points`)
must equal the per-sample rule the trace applied before, written out here with Python
floats, on every kind of surface; the joints' margins are the distances to the range
ends of the recorded joints.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dualarm_qp.control.rollout import rollout
from dualarm_qp.control.trace import grasp_margin, grasp_margins
from dualarm_qp.experiments import build_experiment, load_config
from dualarm_qp.task.surfaces import CurvedBar, CylinderSurface, GraspSurface, PlaneBar

CONFIGS = Path(__file__).resolve().parents[2] / "configs"

SURFACES: dict[str, GraspSurface] = {
    "plane_bar_paper": PlaneBar(),
    "plane_bar_tilted": PlaneBar(r_min=(-1.0, -0.3, -1.0), r_max=(1.0, 1.0, 0.7),
                                 origin=(0.1, 0.2, 0.0), sliding=(0.0, 1.0, 1.0),
                                 normal=(1.0, 1.0, -1.0)),
    "cylinder": CylinderSurface(0.05, azimuth=0.7, sigma_min=-0.1, sigma_max=0.3),
    "curved": CurvedBar(0.5, sigma_min=-0.2, sigma_max=0.6),
}


def per_sample(surface: GraspSurface, sigma: float) -> float:
    """The per-sample rule, as the trace applied it sample by sample."""
    margin = min(sigma - surface.sigma_min, surface.sigma_max - sigma)
    if not (np.isfinite(surface.r_min).any() or np.isfinite(surface.r_max).any()):
        return float(margin)
    r = surface.point(sigma)
    s = surface.tangent(sigma)
    for i in range(3):
        if abs(s[i]) < 1e-12:
            continue
        for bound, sign in ((surface.r_min[i], 1.0), (surface.r_max[i], -1.0)):
            if math.isfinite(bound):
                margin = min(margin, sign * (r[i] - bound) / abs(s[i]))
    return float(margin)


@settings(max_examples=40, deadline=None)
@given(name=st.sampled_from(sorted(SURFACES)),
       sigmas=st.lists(st.floats(-1.0, 1.5, allow_nan=False), min_size=1, max_size=30))
def test_the_vectorised_margins_equal_the_per_sample_rule(name: str, sigmas: list[float]
                                                          ) -> None:
    surface = SURFACES[name]
    out = grasp_margins(surface, np.array(sigmas))
    assert out.shape == (len(sigmas),)
    assert out.tolist() == [per_sample(surface, s) for s in sigmas]
    assert grasp_margin(surface, sigmas[0]) == per_sample(surface, sigmas[0])


@pytest.mark.parametrize("name", sorted(SURFACES))
def test_points_and_tangents_are_the_per_value_ones(name: str) -> None:
    surface = SURFACES[name]
    sigmas = np.linspace(-0.3, 0.8, 7)
    assert np.array_equal(surface.points(sigmas), np.array([surface.point(s) for s in sigmas]))
    assert np.array_equal(surface.tangents(sigmas),
                          np.array([surface.tangent(s) for s in sigmas]))


@pytest.mark.parametrize("name", ["puma_beam_limits", "both_sliding_bar"])
def test_a_runs_margins_are_the_distances_of_its_recorded_positions(name: str) -> None:
    path = CONFIGS / f"{name}.yaml"
    exp = build_experiment(load_config(path), str(path))
    ctrl = exp.controller()
    tr = rollout(ctrl, exp.initial, duration=0.2, limits=exp.limits).trace
    task = exp.task
    assert len(tr) > 5
    for k in range(len(tr)):
        assert np.array_equal(tr.margin_qf[k], np.minimum(tr.q_f[k] - task.follower.q_min,
                                                          task.follower.q_max - tr.q_f[k]))
        assert np.array_equal(tr.margin_ql[k], np.minimum(tr.q_l[k] - task.leader.q_min,
                                                          task.leader.q_max - tr.q_l[k]))
        assert tr.margin_grasp[k] == per_sample(task.surface, float(tr.grasp[k]))
        if task.leader_surface is not None:
            assert tr.margin_grasp_leader[k] == per_sample(task.leader_surface,
                                                           float(tr.grasp_leader[k]))
