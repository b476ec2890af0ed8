"""The compiled collision parts: the scene's measure and the damper's rows.

* the rows from the kernel (``damper_rows``) equal ``n^T (J_a(p_a) - J_b(p_b))`` written
  out here with Pinocchio's Python API (each arm's model, its frame Jacobian and the point
  offset), for both set-ups of ``test_collision_rows`` at seeded random states;
* the kernel's measure of every capsule pair equals coal's distance of the placed shapes;
* the limit's one kernel call (``DamperScene.rows``) equals its steps called one by one
  (the frame stack, the measure within ``d_i``, the pairs closer than ``d_i``, their rows
  and bounds, the rows that move), bit for bit; a non-finite frame is an error, and the
  limit pickles and copies;
* a scene with box pairs pickles after measuring (the kernel's coal solvers stay behind
  and are made again) and measures the same after;
* arrays of inconsistent shapes and unknown owners or frames are errors, not crashes;
  broadcast (zero-stride) and Fortran-ordered arrays are read as their values.
"""

from __future__ import annotations

import copy
import pickle

import numpy as np
import pinocchio as pin
import pytest
from collision_setups import experiment
from test_collision_rows import BOTH_SLIDING, PUMA, _random_state, needs_robots

from dualarm_qp._compiled import kernel
from dualarm_qp.collision.scene import OWNERS
from dualarm_qp.errors import NonFiniteError
from dualarm_qp.geometry import Capsule, capsule_proximities
from dualarm_qp.geometry.distance import coal_proximity, coal_shape
from dualarm_qp.step.limits.collision import ZERO_ROW, CollisionLimit


@pytest.fixture(scope="module", params=[
    pytest.param(PUMA, id="puma_beam"),
    pytest.param(BOTH_SLIDING, id="both_sliding_bar", marks=needs_robots)])
def setup(request: pytest.FixtureRequest):
    exp = experiment(*request.param)
    builder = exp.controller().builder
    limit = next(lim for lim in builder.limits if isinstance(lim, CollisionLimit))
    return exp, builder, limit


def _point_row(arm, frame: int, point: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """``n^T J(point)`` of a point fixed to ``frame``, with Pinocchio's Python API."""
    data = arm.data
    J = pin.getFrameJacobian(arm.model, data, frame, pin.LOCAL_WORLD_ALIGNED)
    origin = data.oMf[frame].translation
    J_point = J[:3] - pin.skew(point - origin) @ J[3:]
    return normal @ J_point[:, :arm.n_joints]


@pytest.mark.parametrize("seed", range(3))
def test_rows_equal_the_jacobians_written_out(setup, seed: int) -> None:
    exp, builder, limit = setup
    ctx = builder.build(_random_state(exp, builder.layout, np.random.default_rng(seed))).context
    c = limit.constraint(ctx)
    assert c.G is not None and c.G.shape[0] > 5
    lay = builder.layout
    scene = limit.scene
    pair_of = {f"clearance {p.name}": p for p in scene.pairs}
    measured = scene.measure(limit.frames(ctx))
    where = {int(k): j for j, k in enumerate(measured.pairs.tolist())}
    for row, name in zip(c.G, c.row_names, strict=True):
        pair = pair_of[name]
        j = where[scene.pairs.index(pair)]
        prox = measured.prox[j]
        expected = np.zeros(lay.n)
        for body, point, sign in ((pair.a, prox.point_a, 1.0), (pair.b, prox.point_b, -1.0)):
            b = scene.bodies[body]
            if b.owner == "world":
                continue
            if b.owner == "object":
                J = ctx.carry.J_object
                r = point - ctx.carry.T_object[:3, 3]
                n_row = prox.normal @ (J[:3] - pin.skew(r) @ J[3:])
                expected[lay.leader] += sign * n_row[:lay.n_l]
                expected[lay.grasps] += sign * n_row[lay.n_l:]
                continue
            leader = b.owner == "leader"
            arm = ctx.leader_arm if leader else ctx.follower_arm
            frame = limit._frames[0 if leader else 1][b.link]
            expected[lay.leader if leader else lay.follower] += sign * _point_row(
                arm, frame, point, prox.normal)
        np.testing.assert_allclose(row, expected, rtol=0.0, atol=1e-12)


def test_measure_places_every_body_and_pair(setup) -> None:
    """The kernel's measure (placing, broad phase off) against coal on the placed shapes.

    Coal's capsule distance is an implementation of its own (an iterative one): the
    distances agree to 1e-8 m (2e-9 m seen). Witness points and normals are compared
    with the closed form called pair by pair on the shapes placed in Python (the same
    closed form: this checks the kernel's placement and the pairs' order).
    """
    exp, builder, limit = setup
    ctx = builder.build(exp.initial).context
    scene = limit.scene
    frames = limit.frames(ctx)
    placed = scene.placed(frames)
    measured = scene.measure(frames)
    assert measured.pairs.tolist() == list(range(len(scene.pairs)))
    capsules = 0
    for j, pair in enumerate(scene.pairs):
        a, b = placed[pair.a], placed[pair.b]
        if not (isinstance(a, Capsule) and isinstance(b, Capsule)):
            continue
        capsules += 1
        got = measured.prox[j]
        by_coal = coal_proximity(*coal_shape(a), *coal_shape(b))
        assert got.distance == pytest.approx(by_coal.distance, abs=1e-8)
        one = capsule_proximities(a.a[None], a.b[None], [a.radius], b.a[None], b.b[None],
                                  [b.radius])[0]
        assert got.distance == pytest.approx(one.distance, abs=1e-14)
        for u, v in ((got.point_a, one.point_a), (got.point_b, one.point_b),
                     (got.normal, one.normal)):
            np.testing.assert_allclose(u, v, rtol=0.0, atol=1e-13)
    assert capsules > 10


def _rows_one_by_one(limit: CollisionLimit, ctx) -> tuple[list[str], np.ndarray, np.ndarray]:
    """The damper's rows by the kernel's separate calls, as the limit once made them."""
    scene, lay = limit.scene, limit.layout
    measured = scene.measure(limit.frames(ctx), within=limit._d_i)
    prox = measured.prox
    near = np.flatnonzero(prox.distance < limit._d_i)
    pairs = measured.pairs[near]
    owner = [OWNERS.index(b.owner) for b in scene.bodies]
    frame = [limit._frames[OWNERS.index(b.owner)][b.link]
             if b.owner in ("leader", "follower") else -1 for b in scene.bodies]
    ends = [i for k in pairs.tolist() for i in (scene.pairs[k].a, scene.pairs[k].b)]
    G = kernel.damper_rows(
        ctx.leader_arm.chain, ctx.follower_arm.chain, ctx.carry.J_object,
        ctx.carry.T_object[:3, 3], [owner[i] for i in ends], [frame[i] for i in ends],
        prox.point_a[near], prox.point_b[near], prox.normal[near], lay.n_l, lay.n_f,
        lay.grasps.start, lay.n)
    h = limit._gain * (prox.distance[near] - limit._d_s)
    moving = np.abs(G).max(axis=1) > ZERO_ROW
    names = [f"clearance {scene.pairs[k].name}" for k in pairs.tolist()]
    return [n for n, m in zip(names, moving.tolist(), strict=True) if m], G[moving], h[moving]


@pytest.mark.parametrize("seed", range(4))
def test_one_call_is_the_steps_one_by_one(setup, seed: int) -> None:
    exp, builder, limit = setup
    ctx = builder.build(_random_state(exp, builder.layout, np.random.default_rng(seed))).context
    got = limit.constraint(ctx)
    names, G, h = _rows_one_by_one(limit, ctx)
    assert list(got.row_names) == names
    assert got.G is not None and got.h is not None
    np.testing.assert_array_equal(got.G, G)
    np.testing.assert_array_equal(got.h, h)


def test_unmoved_pairs_leave_no_row() -> None:
    """The PUMA set-up's ball lies on the leader's first joint axis: zero rows are left out."""
    exp = experiment(*PUMA)
    builder = exp.controller().builder
    limit = next(lim for lim in builder.limits if isinstance(lim, CollisionLimit))
    ctx = builder.build(exp.initial).context
    names, _, _ = _rows_one_by_one(limit, ctx)
    measured = limit.scene.measure(limit.frames(ctx), within=limit._d_i)
    near = int(np.count_nonzero(measured.prox.distance < limit._d_i))
    got = limit.constraint(ctx).row_names
    assert list(got) == names and 0 < len(got) < near


def test_a_scene_without_boxes() -> None:
    """No pair with a box: the scene has no coal objects and the rows are the same."""
    name, extra = PUMA
    obstacles = [o for o in extra["scene"]["obstacles"] if "box" not in o]
    exp = experiment(name, {**extra, "scene": {"obstacles": obstacles}})
    builder = exp.controller().builder
    limit = next(lim for lim in builder.limits if isinstance(lim, CollisionLimit))
    assert limit.scene._exact is None
    for seed in range(3):
        ctx = builder.build(_random_state(exp, builder.layout,
                                               np.random.default_rng(seed))).context
        got = limit.constraint(ctx)
        names, G, h = _rows_one_by_one(limit, ctx)
        assert list(got.row_names) == names and names
        np.testing.assert_array_equal(got.G, G)
        np.testing.assert_array_equal(got.h, h)


@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_a_non_finite_frame_or_jacobian_is_an_error(setup, bad: float) -> None:
    exp, builder, limit = setup
    # The object's pose, then each column of its Jacobian in turn (the object's rows read
    # them all), made non-finite in the step's own context.
    n_cols = builder.build(exp.initial).context.carry.J_object.shape[1]
    for where in ["T", *range(n_cols)]:
        ctx = builder.build(exp.initial).context
        kctx = ctx.kernel_context
        if where == "T":
            kctx.T_object[0, 3] = bad
        else:
            kctx.J_object[0, where] = bad
        with pytest.raises(NonFiniteError, match="collision rows"):
            limit.constraint(ctx)


def test_the_limit_pickles_and_copies(setup) -> None:
    exp, builder, limit = setup
    ctx = builder.build(exp.initial).context
    before = limit.constraint(ctx)
    for other in (pickle.loads(pickle.dumps(limit)), copy.deepcopy(limit)):
        assert other._damper is not limit._damper
        after = other.constraint(ctx)
        assert after.row_names == before.row_names
        np.testing.assert_array_equal(after.G, before.G)
        np.testing.assert_array_equal(after.h, before.h)


def test_scene_with_box_pairs_pickles_after_measuring(setup) -> None:
    exp, builder, limit = setup
    ctx = builder.build(exp.initial).context
    frames = limit.frames(ctx)
    before = limit.scene.measure(frames)
    assert limit.scene._exact is not None  # the box pairs' kernel solvers
    copy = pickle.loads(pickle.dumps(limit.scene))
    after = copy.measure(frames)
    assert np.array_equal(before.pairs, after.pairs)
    assert np.array_equal(before.prox.distance, after.prox.distance)


def test_bad_arrays_are_errors(setup) -> None:
    exp, builder, limit = setup
    ctx = builder.build(exp.initial).context
    scene, lay = limit.scene, builder.layout
    frames = limit.frames(ctx).reshape(-1, 4)
    nb = len(scene.bodies)
    a, b, r, sphere = scene._a, scene._b, scene._r, scene._sphere
    with pytest.raises(ValueError, match="inconsistent"):
        kernel.scene_proximities(frames[:-1], scene._frame_list, a, b, r, sphere, [0], [1],
                                 np.inf)
    with pytest.raises(ValueError, match="no such frame"):
        kernel.scene_proximities(frames, [10_000] * nb, a, b, r, sphere, [0], [1], np.inf)
    with pytest.raises(ValueError, match="no such body"):
        kernel.scene_proximities(frames, scene._frame_list, a, b, r, sphere, [0], [nb],
                                 np.inf)
    chains = (ctx.leader_arm.chain, ctx.follower_arm.chain, ctx.carry.J_object,
              ctx.carry.T_object[:3, 3])
    pts = np.zeros((1, 3))
    n = np.array([[0.0, 0.0, 1.0]])
    with pytest.raises(ValueError, match="inconsistent"):
        kernel.damper_rows(*chains, [0], [1], pts, pts, n, lay.n_l, lay.n_f,
                           lay.grasps.start, lay.n)
    with pytest.raises(ValueError, match="owner"):
        kernel.damper_rows(*chains, [7, 3], [1, -1], pts, pts, n, lay.n_l, lay.n_f,
                           lay.grasps.start, lay.n)
    # A broadcast (zero-stride) or Fortran-ordered array is read as its values (copied).
    frame = limit._frames[0][3]
    broadcast = np.broadcast_to(np.array([0.0, 0.6, 0.8]), (3, 3))
    away = np.array([[0.3, 0.2, 0.5]]).repeat(3, 0)
    args = ([0, 3] * 3, [frame, -1] * 3, away, away)
    rows = kernel.damper_rows(*chains, *args, np.array(broadcast), lay.n_l, lay.n_f,
                              lay.grasps.start, lay.n)
    assert np.abs(rows).max() > 0.0
    for odd in (broadcast, np.asfortranarray(broadcast)):
        np.testing.assert_array_equal(kernel.damper_rows(
            *chains, *args, odd, lay.n_l, lay.n_f, lay.grasps.start, lay.n), rows)
    end = np.broadcast_to(np.array([1.0, 0.0, 0.0]), (4, 3))
    one = kernel.capsule_proximities(np.zeros((4, 3)), np.array(end), np.ones(4),
                                     np.array(end) + 1.0, np.array(end) + 2.0, np.ones(4))
    got = kernel.capsule_proximities(np.zeros((4, 3)), end, np.ones(4), end + 1.0, end + 2.0,
                                     np.ones(4))
    for name in ("distance", "point_a", "point_b", "normal"):
        np.testing.assert_array_equal(getattr(one, name), getattr(got, name))
    with pytest.raises(IndexError, match="no frame"):
        kernel.damper_rows(*chains, [0, 3], [10_000, -1], pts, pts, n, lay.n_l, lay.n_f,
                           lay.grasps.start, lay.n)
