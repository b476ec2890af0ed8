"""The collision rows' derivatives match finite differences of the distances.

A row of :class:`~dualarm_qp.step.limits.collision.CollisionLimit` is ``G x <= h`` with
``G x = -d_dot``: minus the rate of change of the pair's distance when the decision
vector ``x`` (both arms' joint rates and every sliding speed) is applied. Here the
state itself is moved, ``+-eps x`` (the leader's joints, the follower's, the follower's
grasp and a sliding leader grasp: the object moves with the leader's tool and its
grasp), every pair is measured again with the scene, and ``-(d(+eps) - d(-eps)) / 2 eps``
is compared with ``G x`` for every row.

Set-ups (influence distance 5 m, so that every pair gives a row): the PUMA beam task
with a capsule object, a ball by the follower's elbow, a post by the leader's forearm
and a turned crate by the object (arm-arm, arm-object, arm-obstacle and
object-obstacle pairs, capsules and boxes); two UR5s carrying a box-shaped bar with both
grasps sliding, a turned crate under the bar and a ball (the grasp columns). States:
the start with seeded random offsets (joints 0.05 rad, grasps 10 mm).

Excluded: capsule pairs whose axes are within 1e-3 rad of parallel (their witness
points are not unique and the distance has a kink under rotation). At these states the
only one is the UR5s' two base capsules, which no joint moves (their row is zero). Measured
agreement: about 4e-10 per unit ``x`` (central differences, eps = 1e-6), asserted at 1e-7.
"""

from __future__ import annotations

import numpy as np
import pytest
from collision_setups import experiment, merged

from dualarm_qp.geometry.shapes import Capsule
from dualarm_qp.kinematics.robots import example_robots_dir
from dualarm_qp.step.limits.collision import ROW_PREFIX, CollisionLimit
from dualarm_qp.step.state import DualArmState

EPS = 1e-6
TOL = 1e-7           # |G x - finite difference| per unit |x|_inf
PARALLEL = 1e-3      # sine of the angle below which a capsule pair is left out
#: The parallel pairs the set-ups have: two bodies fixed to the arms' bases.
FIXED_PARALLEL = {"leader.base - follower.base"}

PUMA = ("puma_beam_limits", {
    "collision": {"enabled": True, "influence_distance": 5000},
    "object": {"shape": {"capsule": {"radius": 25, "length": 500},
                         "pose": {"position": [0, 0, 250]}}},
    "scene": {"obstacles": [
        {"name": "ball", "sphere": {"radius": 50}, "pose": {"position": [-12, 1137, -400]}},
        {"name": "post", "capsule": {"radius": 30, "length": 600},
         "pose": {"position": [100, 400, 200], "rpy": [0, 80, 0]}},
        {"name": "crate", "box": {"size": [100, 150, 80]},
         "pose": {"position": [0, 900, 380], "rpy": [10, 20, 30]}}]}})
BOTH_SLIDING = ("both_sliding_bar", {
    "collision": {"enabled": True, "influence_distance": 5000},
    "object": {"shape": {"box": {"size": [40, 40, 900]}, "pose": {"position": [20, 0, 400]}}},
    "scene": {"obstacles": [
        {"name": "crate", "box": {"size": [100, 100, 100]},
         "pose": {"position": [700, 120, 150], "rpy": [0, 0, 20]}},
        {"name": "ball", "sphere": {"radius": 60}, "pose": {"position": [600, -300, 500]}}]}})

needs_robots = pytest.mark.skipif(example_robots_dir() is None,
                                  reason="example-robot-data is not installed")


@pytest.fixture(scope="module", params=[
    pytest.param(PUMA, id="puma_beam"),
    pytest.param(BOTH_SLIDING, id="both_sliding_bar", marks=needs_robots)])
def setup(request: pytest.FixtureRequest):
    exp = experiment(*request.param)
    controller = exp.controller()
    limit = next(lim for lim in controller.builder.limits if isinstance(lim, CollisionLimit))
    return exp, controller.builder, limit


def _distances(task, state: DualArmState) -> dict[str, float]:
    """Every pair's distance at ``state``, measured with the scene [m]."""
    scene = task.scene
    frames = scene.frames(task.leader.link_frames(state.q_l),
                          task.follower.link_frames(state.q_f),
                          task.leader.fk(state.q_l) @ task.H1_at(state.sigma_leader))
    return dict(zip(scene.pair_names, scene.measure(frames).prox.distance.tolist(),
                    strict=True))


def _moved(state: DualArmState, layout, dx: np.ndarray) -> DualArmState:
    ql, qf, m, m_l = layout.split(dx)
    return DualArmState(state.t, state.q_l + ql, state.q_f + qf, state.sigma + m,
                        state.sigma_leader + m_l)


def _random_state(exp, layout, rng: np.random.Generator) -> DualArmState:
    s = exp.initial
    return DualArmState(s.t, s.q_l + rng.normal(0, 0.05, s.q_l.size),
                        s.q_f + rng.normal(0, 0.05, s.q_f.size),
                        s.sigma + rng.normal(0, 0.01),
                        s.sigma_leader + (rng.normal(0, 0.01)
                                          if layout.grasp_leader is not None else 0.0))


def _parallel_pairs(task, state: DualArmState) -> set[str]:
    """Capsule pairs (both of non-zero length) whose axes are within PARALLEL of parallel."""
    scene = task.scene
    frames = scene.frames(task.leader.link_frames(state.q_l),
                          task.follower.link_frames(state.q_f),
                          task.leader.fk(state.q_l) @ task.H1_at(state.sigma_leader))
    placed = scene.placed(frames)
    out = set()
    for pair in scene.pairs:
        a, b = placed[pair.a], placed[pair.b]
        if isinstance(a, Capsule) and isinstance(b, Capsule) and a.length and b.length:
            u, v = (a.b - a.a) / a.length, (b.b - b.a) / b.length
            if np.linalg.norm(np.cross(u, v)) < PARALLEL:
                out.add(pair.name)
    return out


@pytest.mark.parametrize("seed", range(4))
def test_rows_match_finite_differences(setup, seed: int) -> None:
    exp, builder, limit = setup
    task, layout = exp.task, builder.layout
    rng = np.random.default_rng(seed)
    state = _random_state(exp, layout, rng)
    ctx = builder.build(state).context
    rows = limit.constraint(ctx)
    pairs = [name[len(ROW_PREFIX):] for name in rows.row_names]
    # Every pair is within d_i = 5 m; the ones without a row are those no variable moves
    # at this state (a sphere on its joint's axis): their distance does not change.
    unmoved = sorted(set(task.scene.pair_names) - set(pairs))
    assert set(pairs) <= set(task.scene.pair_names)
    skip = _parallel_pairs(task, state)
    assert skip <= FIXED_PARALLEL
    keep = np.array([p not in skip for p in pairs])
    for _ in range(3):
        x = rng.normal(size=layout.n)
        plus = _distances(task, _moved(state, layout, EPS * x))
        minus = _distances(task, _moved(state, layout, -EPS * x))
        fd = np.array([-(plus[p] - minus[p]) / (2 * EPS) for p in pairs])
        for p in unmoved:
            assert abs(plus[p] - minus[p]) / (2 * EPS) <= TOL * np.max(np.abs(x)), p
        err = np.where(keep, np.abs(rows.G @ x - fd), 0.0)
        worst = int(np.argmax(err))
        assert err[worst] <= TOL * np.max(np.abs(x)), (
            f"{pairs[worst]}: G x = {(rows.G @ x)[worst]!r}, finite difference {fd[worst]!r}")
    # What the set-up covers.
    groups = {p.group for p in task.scene.pairs}
    assert {"arm_arm", "arm_object", "obstacle"} <= groups
    assert "object - crate" in pairs


def test_grasp_columns(setup) -> None:
    """The follower's grasp moves no body (its column is zero); a sliding leader grasp
    moves the object only (its column is non-zero in rows of the object only; it may be
    zero there too, where the slide runs along the object's face)."""
    exp, builder, limit = setup
    layout = builder.layout
    rows = limit.constraint(builder.build(_random_state(exp, layout,
                                                          np.random.default_rng(9))).context)
    assert np.all(rows.G[:, layout.grasp_follower] == 0.0)
    if layout.grasp_leader is None:
        return
    with_object = np.array(["object" in n[len(ROW_PREFIX):].split(" - ")
                            for n in rows.row_names])
    column = np.abs(rows.G[:, layout.grasp_leader])
    assert np.any(column[with_object] > 0.1)
    assert np.all(column[~with_object] == 0.0)


@pytest.mark.parametrize("seed", range(3))
def test_rows_are_the_pairs_closer_than_d_i(seed: int) -> None:
    """With the default influence distance (100 mm) a row comes for exactly the pairs
    closer than d_i, with ``h = xi (d - d_s) / (d_i - d_s)``."""
    name, extra = PUMA
    extra = merged(extra, {"collision": {"influence_distance": 100}})
    exp = experiment(name, extra)
    builder = exp.controller().builder
    limit = next(lim for lim in builder.limits if isinstance(lim, CollisionLimit))
    rng = np.random.default_rng(100 + seed)
    state = _random_state(exp, builder.layout, rng)
    rows = limit.constraint(builder.build(state).context)
    d = _distances(exp.task, state)
    s = exp.task.scene.settings
    near = sorted(p for p, v in d.items() if v < s.influence_distance)
    got = [n[len(ROW_PREFIX):] for n in rows.row_names]
    assert sorted(got) == near and near
    expected_h = np.array([s.approach_speed_max * (d[p] - s.safety_distance) / s.band
                           for p in got])
    assert np.allclose(rows.h, expected_h, rtol=0, atol=1e-12)
