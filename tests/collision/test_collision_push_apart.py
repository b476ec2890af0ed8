"""Touching and penetrating shapes keep a row, and the solved step pushes them apart.

Below the safety distance the velocity damper's right-hand side ``h = xi (d - d_s) /
(d_i - d_s)`` is negative: the row asks the pair to separate at ``-h`` at least. Checked
on the PUMA beam task with a ball by the follower's upper arm (link2, radius 100 mm):

* a start within d_s (18 mm apart): the row is there at the start, ``h < 0``, and every
  step of the run widens the gap;
* at a state of the nominal motion (t = 3.1 s), a ball placed off link2's axis so that
  the shapes are 10 mm apart, touching (0 mm) or overlapping by 120 mm, and a ball
  centred ON the axis (the axes meet: no normal from the witness points, the fallback
  one): the row's ``h`` is negative, its ``G`` is non-zero, and one controller step
  increases the distance by at least ``-h dt`` to first order (0.9 of it asserted).

A deep overlap asks for a fast separation, ``-h`` = 0.35 m/s at 120 mm with the default
settings. Along the fallback normal of a ball on the axis (fixed by the geometry alone)
the follower cannot move that fast with the path held (status ERROR: no step), while a
ball 30 mm off the axis at the same depth is pushed out along the witness normal. The
axis case is therefore checked with a 1 m influence distance (``-h`` = 29 mm/s).
"""

from __future__ import annotations

import numpy as np
import pytest
from collision_setups import experiment, load, merged

from dualarm_qp.control.rollout import rollout
from dualarm_qp.experiments.config import parse_config
from dualarm_qp.experiments.setup import build_experiment
from dualarm_qp.step.limits.collision import ROW_PREFIX, CollisionLimit
from dualarm_qp.step.state import DualArmState

PAIR = "follower.link2 - ball"
LINK2_RADIUS = 0.10


def _ball(position_m, radius_m: float, influence_mm: float = 100.0) -> dict:
    return {"collision": {"enabled": True, "influence_distance": influence_mm},
            "scene": {"obstacles": [{"name": "ball", "sphere": {"radius": radius_m * 1e3},
                                     "pose": {"position": (np.asarray(position_m) * 1e3)
                                              .tolist()}}]}}


def _distance(task, state: DualArmState, pair: str = PAIR) -> float:
    scene = task.scene
    frames = scene.frames(task.leader.link_frames(state.q_l),
                          task.follower.link_frames(state.q_f),
                          task.leader.fk(state.q_l) @ task.H1_at(state.sigma_leader))
    return float(scene.measure(frames).prox.distance[scene.pair_names.index(pair)])


def _row(controller, state: DualArmState, pair: str = PAIR) -> tuple[np.ndarray, float]:
    builder = controller.builder
    limit = next(lim for lim in builder.limits if isinstance(lim, CollisionLimit))
    rows = limit.constraint(builder.build(state).context)
    i = list(rows.row_names).index(ROW_PREFIX + pair)
    return rows.G[i], float(rows.h[i])


def test_a_start_within_d_s_is_pushed_out_step_by_step() -> None:
    """A ball 18 mm from the follower's elbow (link3) at the start, d_s = 20 mm."""
    pair = "follower.link3 - ball"
    # The ball also overlaps the upper arm (link2) at the start: that pair is excluded
    # by name (an obstacle overlapping an arm at the start is otherwise refused).
    exp = experiment("puma_beam_limits", merged(
        _ball([0.155, 1.145, -0.210], 0.05),
        {"controller": {"duration": 0.31},
         "collision": {"exclude": [["follower.link2", "ball"]]}}))
    d_s = exp.task.scene.settings.safety_distance
    d0 = _distance(exp.task, exp.initial, pair)
    assert 0.0 < d0 < d_s and pair in exp.task.scene.pair_names
    controller = exp.controller()
    G, h = _row(controller, exp.initial, pair)
    assert h < 0.0 and np.linalg.norm(G) > 0.0
    out = controller.step(exp.initial)
    assert out.applied
    d1 = _distance(exp.task, exp.initial.advanced(out, exp.options.dt), pair)
    assert d1 - d0 >= 0.9 * -h * exp.options.dt
    # A short run: the recorded clearance widens at every sample (without the check
    # before the run, which refuses this start: the record could not keep d_s there).
    res = rollout(exp.controller(), exp.initial, duration=exp.duration, limits=exp.limits,
                  project=exp.project, preflight=False)
    gap = res.trace.clearance_obstacles
    assert len(gap) > 5 and np.all(np.diff(gap) > 0.0), gap


@pytest.fixture(scope="module")
def nominal():
    """The state of the beam task after 3.1 s (no scene), and link2's geometry there."""
    data = merged(load("puma_beam_limits"), {"controller": {"duration": 3.1}})
    exp = build_experiment(parse_config(data, "nominal"), "nominal", solver="nullspace")
    res = rollout(exp.controller(), exp.initial, duration=exp.duration, limits=exp.limits,
                  project=exp.project)
    assert res.completed
    tr, k = res.trace, len(res.trace) - 1
    state = DualArmState(float(tr.tau[k]), tr.q_l[k].copy(), tr.q_f[k].copy(),
                         float(tr.grasp[k]))
    F = exp.task.follower.link_frames(state.q_f)
    F0 = exp.task.follower.link_frames(exp.initial.q_f)
    a, b = F[1, :3, 3], F[2, :3, 3]           # link2's axis: shoulder to elbow
    axis = (b - a) / np.linalg.norm(b - a)
    # Off the axis, away from where link2 was at the start (the start stays clear).
    away = b - F0[2, :3, 3]
    away -= axis * (away @ axis)
    return state, a + 0.85 * (b - a), away / np.linalg.norm(away)


@pytest.mark.parametrize(("offset", "radius", "influence_mm", "expected"), [
    pytest.param(0.16, 0.05, 100.0, 0.01, id="10mm-apart"),
    pytest.param(0.15, 0.05, 100.0, 0.0, id="touching"),
    pytest.param(0.03, 0.05, 100.0, -0.12, id="overlapping-120mm"),
    pytest.param(0.0, 0.02, 1000.0, -0.12, id="axes-meet-120mm"),
])
def test_touching_and_overlapping_shapes_are_pushed_apart(nominal, offset: float,
                                                          radius: float, influence_mm: float,
                                                          expected: float) -> None:
    state, on_axis, away = nominal
    exp = experiment("puma_beam_limits", _ball(on_axis + offset * away, radius, influence_mm))
    assert PAIR in exp.task.scene.pair_names          # clear at the start: not left out
    d0 = _distance(exp.task, state)
    assert abs(d0 - expected) < 1e-9
    assert abs(d0 - (offset - LINK2_RADIUS - radius)) < 1e-9
    if offset == 0.0:  # the axes meet (to rounding): the normal is the fallback one
        assert abs(d0 + LINK2_RADIUS + radius) <= 1e-12
    controller = exp.controller()
    G, h = _row(controller, state)
    s = exp.task.scene.settings
    assert h < 0.0 and abs(h - s.approach_speed_max * (d0 - s.safety_distance) / s.band) < 1e-12
    assert np.linalg.norm(G) > 0.1
    out = controller.step(state)
    assert out.applied, out.status
    d1 = _distance(exp.task, state.advanced(out, exp.options.dt))
    assert d1 - d0 >= 0.9 * -h * exp.options.dt, (d0, d1, h)


def test_a_pair_that_cannot_be_pushed_apart_is_named_plainly(nominal) -> None:
    """The ball on link2's axis, 120 mm deep, with the default influence distance: no step
    separates them as fast as the row asks (the case above that needs 1 m). The run's
    failure names the pair and how deep it is first (criterion ``collision``), then the
    policy's "no common point" and the limits in conflict."""
    state, on_axis, _ = nominal
    exp = experiment("puma_beam_limits", merged(_ball(on_axis, 0.02),
                                                {"controller": {"duration": 3.5}}))
    d0 = _distance(exp.task, state)
    assert abs(d0 + 0.12) < 1e-9
    res = rollout(exp.controller(), state, duration=0.3, limits=exp.limits, preflight=False)
    failure = res.failure
    assert failure is not None and failure.criterion == "collision" and failure.sample == 0
    assert failure.amount == pytest.approx(d0, abs=1e-12) and failure.limit == 0.02
    assert failure.message.startswith(
        f"step 0 at t = {state.t:.4f} s: no step keeps every limit: collision pair {PAIR} "
        "overlaps by 120.00 mm, closer than its safety distance of 20 mm, and cannot be "
        "moved apart as fast as its limit asks (solver status error: the limits admit no "
        "common point: cannot relax; conflicting: "), failure.message
    assert f"clearance {PAIR}" in failure.message
