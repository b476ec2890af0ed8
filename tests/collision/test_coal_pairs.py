"""The scene's pairs with a box, measured by coal inside the kernel (``kernel.CoalPairs``).

* at the same poses, the kernel's answer is coal's Python answer (``coal_proximity``)
  bit for bit (the unit normal to its last bit), for boxes against boxes, capsules and
  spheres, apart and overlapping;
* a body posed in its frame by a local pose: the same to rounding (the pose product is
  the kernel's own);
* the scene's measure is the rule stated in :meth:`CollisionScene.measure`, written out
  here with the capsule-only measure, the box's slabs in numpy and coal's Python API:
  every pair with a box whose capsule bound and slab bound are both below ``within`` is
  coal's, the others with a box are dropped (every one is coal's when ``within`` is
  infinite);
* a non-finite frame is a :class:`NonFiniteError`, inconsistent arrays and unknown
  kinds are errors, and a kernel built with another coal is refused at import.
"""

from __future__ import annotations

import copy
import pickle

import numpy as np
import pinocchio as pin
import pytest
from collision_setups import experiment
from hypothesis import given, settings
from hypothesis import strategies as st
from test_collision_rows import PUMA

from dualarm_qp._compiled import check_coal, kernel
from dualarm_qp.errors import KernelError, NonFiniteError
from dualarm_qp.geometry import Box, Capsule
from dualarm_qp.geometry.distance import (
    EPA_TOLERANCE,
    GJK_TOLERANCE,
    Proximities,
    coal_parts,
    coal_proximity,
    coal_shape,
)
from dualarm_qp.step.limits.collision import CollisionLimit

SIZES = st.floats(0.01, 1.0)


def _shape(kind: int, sizes: tuple[float, float, float]) -> Box | Capsule:
    """A box, a capsule along a tilted axis, or a sphere (a zero-length capsule)."""
    if kind == 0:
        return Box(np.array(sizes))
    a = np.array([0.1, -0.2, 0.05])
    b = a + (np.array([sizes[0], -sizes[1], 0.3]) if kind == 1 else 0.0)
    return Capsule(a, b, sizes[2] / 2)


def _pairs(box: Box, other: Box | Capsule) -> kernel.CoalPairs:
    """The kernel's coal pair (box, other), with local poses of the shapes' own."""
    parts = [coal_parts(box), coal_parts(other)]
    return kernel.CoalPairs([p[0] for p in parts], np.array([p[1] for p in parts]),
                            np.concatenate([p[2] for p in parts]), [0], [1], [True],
                            GJK_TOLERANCE, EPA_TOLERANCE)


def _random_pose(rng: np.random.Generator, spread: float) -> np.ndarray:
    """A pose drawn from ``rng`` alone: a random rotation, a normal offset [m]."""
    T = np.eye(4)
    T[:3, :3] = pin.exp3(rng.normal(0.0, 2.0, 3))
    T[:3, 3] = rng.normal(0.0, spread, 3)
    return T


@settings(max_examples=60, deadline=None, derandomize=True)
@given(kind=st.sampled_from([0, 1, 2]), box=st.tuples(SIZES, SIZES, SIZES),
       other=st.tuples(SIZES, SIZES, SIZES), seed=st.integers(0, 2**32 - 1),
       spread=st.sampled_from([0.05, 0.3, 1.0]))
def test_kernel_pair_is_coal_bit_for_bit(kind: int, box: tuple[float, float, float],
                                         other: tuple[float, float, float], seed: int,
                                         spread: float) -> None:
    """Local poses of identity: the kernel places the shapes exactly where Python does."""
    rng = np.random.default_rng(seed)
    a, b = Box(np.array(box)), _shape(kind, other)
    geom_a, geom_b = coal_shape(a)[0], coal_shape(b)[0]
    # Shapes whose own pose is the identity in their frame, placed by the frames alone.
    parts = [coal_parts(a), coal_parts(b)]
    pairs = kernel.CoalPairs([p[0] for p in parts], np.array([p[1] for p in parts]),
                             np.concatenate([np.eye(4), np.eye(4)]), [0], [1], [True],
                             GJK_TOLERANCE, EPA_TOLERANCE)
    for _ in range(5):
        T_a, T_b = _random_pose(rng, spread), _random_pose(rng, spread)
        got = pairs.measure(0, T_a, T_b)
        expected = coal_proximity(geom_a, T_a, geom_b, T_b)
        assert got.distance == expected.distance
        np.testing.assert_array_equal(got.point_a, expected.point_a)
        np.testing.assert_array_equal(got.point_b, expected.point_b)
        # Both divide coal's normal by its length; numpy's dot product (BLAS) may fuse
        # its multiply-adds, so the length may differ in its last bit.
        np.testing.assert_allclose(got.normal, expected.normal, rtol=0.0, atol=4e-16)


@pytest.mark.parametrize("kind", [0, 1, 2], ids=["box", "capsule", "sphere"])
def test_kernel_pair_with_local_poses_is_coal(kind: int) -> None:
    """The shapes' own poses in their frames: the pose product is the kernel's (rounding)."""
    rng = np.random.default_rng(kind)
    box = Box(np.array([0.3, 0.2, 0.1]), pose=_random_pose(rng, 0.05))
    other = _shape(kind, (0.2, 0.1, 0.08))
    pairs = _pairs(box, other)
    (geom_a, local_a), (geom_b, local_b) = coal_shape(box), coal_shape(other)
    seen_overlap = seen_apart = False
    for _ in range(200):
        F_a, F_b = _random_pose(rng, 0.15), _random_pose(rng, 0.15)
        got = pairs.measure(0, F_a, F_b)
        distance, normal = got.distance, got.normal
        expected = coal_proximity(geom_a, F_a @ local_a, geom_b, F_b @ local_b)
        assert distance == pytest.approx(expected.distance, abs=1e-9)
        np.testing.assert_allclose(got.point_a, expected.point_a, rtol=0.0, atol=1e-8)
        np.testing.assert_allclose(got.point_b, expected.point_b, rtol=0.0, atol=1e-8)
        if abs(distance) > 1e-6:
            np.testing.assert_allclose(normal, expected.normal, rtol=0.0, atol=1e-6)
        assert np.linalg.norm(normal) == pytest.approx(1.0, abs=1e-12)
        seen_overlap |= distance < 0.0
        seen_apart |= distance > 0.0
    assert seen_overlap and seen_apart


@pytest.fixture(scope="module")
def scene_setup():
    exp = experiment(*PUMA)
    builder = exp.controller().builder
    limit = next(lim for lim in builder.limits if isinstance(lim, CollisionLimit))
    return exp, builder, limit


def _slab_bound(scene, frames: np.ndarray, box: int, other: int) -> float:
    """The box's slab bound of a pair [m] (``CoalPairs.lower_bound``), in numpy.

    The gaps of the other body's capsule from the box along the box's axes, less its
    radius: a lower bound of their distance where positive (else -inf).
    """
    shape = scene.bodies[box].shape
    T = frames[scene._frame_list[box]] @ shape.pose
    F = frames[scene._frame_list[other]]
    ends = [T[:3, :3].T @ (F[:3, :3] @ e + F[:3, 3] - T[:3, 3])
            for e in (scene._a[other], scene._b[other])]
    lo, hi, h = np.minimum(*ends), np.maximum(*ends), shape.half_size
    apart = float(np.linalg.norm(np.maximum(np.maximum(lo - h, -h - hi), 0.0)))
    apart -= scene._r[other]
    return apart if apart > 0.0 else -np.inf


def _written_out(scene, frames: np.ndarray, within: float) -> tuple[np.ndarray, Proximities]:
    """The rule of :meth:`CollisionScene.measure`, with coal's Python API for the boxes."""
    near = kernel.scene_proximities(
        frames.reshape(-1, 4), scene._frame_list, scene._a, scene._b, scene._r,
        scene._sphere, scene._ia_list, scene._ib_list, within)
    assert near.finite
    prox = zip(near.distance, near.point_a, near.point_b, near.normal, strict=True)
    out_pairs, out = [], []
    for k, (d, pa, pb, n) in zip(near.pairs.tolist(), prox, strict=True):
        pair = scene.pairs[k]
        bodies = (scene.bodies[pair.a], scene.bodies[pair.b])
        if any(isinstance(b.shape, Box) for b in bodies):
            slabs = [_slab_bound(scene, frames, i, j)
                     for i, j in ((pair.a, pair.b), (pair.b, pair.a))
                     if isinstance(scene.bodies[i].shape, Box)]
            if np.isfinite(within) and not max([d, *slabs]) < within:
                continue
            placed = []
            for body, index in zip(bodies, (pair.a, pair.b), strict=True):
                geom, local = coal_shape(body.shape)
                placed += [geom, frames[scene._frame_list[index]] @ local]
            one = coal_proximity(*placed)
            d, pa, pb, n = one.distance, one.point_a, one.point_b, one.normal
        out_pairs.append(k)
        out.append((d, pa, pb, n))
    return np.array(out_pairs), Proximities(np.array([o[0] for o in out]),
                                            *(np.array([o[i] for o in out]) for i in (1, 2, 3)))


@pytest.mark.parametrize("within", [np.inf, 0.3, 0.05])
@pytest.mark.parametrize("seed", range(3))
def test_scene_measure_is_the_rule_written_out(scene_setup, within: float, seed: int) -> None:
    exp, builder, limit = scene_setup
    scene = limit.scene
    assert scene._exact is not None and any(scene._boxed)
    rng = np.random.default_rng(seed)
    lay = builder.layout
    state = copy.copy(exp.initial)
    q_l = state.q_l + rng.normal(0.0, 0.3, lay.n_l)
    q_f = state.q_f + rng.normal(0.0, 0.3, lay.n_f)
    ctx = builder.build(type(state)(state.t, q_l, q_f, state.sigma, state.sigma_leader)).context
    frames = limit.frames(ctx)
    got = scene.measure(frames, within)
    pairs, want = _written_out(scene, frames, within)
    np.testing.assert_array_equal(got.pairs, pairs)
    boxed = np.array([scene._boxed[k] for k in pairs.tolist()], dtype=bool)
    if not np.isfinite(within):
        assert boxed.any()
    np.testing.assert_allclose(got.prox.distance, want.distance, rtol=0.0, atol=1e-9)
    # Capsule pairs are the closed form's, untouched: equal bit for bit.
    np.testing.assert_array_equal(got.prox.distance[~boxed], want.distance[~boxed])
    for u, v in ((got.prox.point_a, want.point_a), (got.prox.point_b, want.point_b)):
        np.testing.assert_allclose(u, v, rtol=0.0, atol=1e-8)


def test_scene_measure_refuses_a_non_finite_frame(scene_setup) -> None:
    exp, builder, limit = scene_setup
    ctx = builder.build(exp.initial).context
    frames = limit.frames(ctx).copy()
    for bad in (np.nan, np.inf, -np.inf):
        off = frames.copy()
        off[2, 0, 3] = bad
        for within in (np.inf, 0.05):  # a body off the numbers is never skipped as far
            with pytest.raises(NonFiniteError, match="collision scene's frames"):
                limit.scene.measure(off, within)


def test_scene_with_box_pairs_copies_and_pickles(scene_setup) -> None:
    """The kernel's object stays behind and is made again: the same answers."""
    exp, builder, limit = scene_setup
    ctx = builder.build(exp.initial).context
    frames = limit.frames(ctx)
    before = limit.scene.measure(frames)
    for other in (pickle.loads(pickle.dumps(limit.scene)), copy.deepcopy(limit.scene)):
        assert other._exact is not None and other._exact is not limit.scene._exact
        after = other.measure(frames)
        np.testing.assert_array_equal(before.pairs, after.pairs)
        np.testing.assert_array_equal(before.prox.distance, after.prox.distance)


def test_bad_coal_pairs_are_errors() -> None:
    box = coal_parts(Box(np.array([0.3, 0.2, 0.1])))
    args = ([box[0], box[0]], np.array([box[1], box[1]]), np.concatenate([box[2], box[2]]))
    tol = (GJK_TOLERANCE, EPA_TOLERANCE)
    with pytest.raises(ValueError, match="inconsistent"):
        kernel.CoalPairs(*args, [0], [1], [True, False], *tol)
    with pytest.raises(ValueError, match="inconsistent"):
        kernel.CoalPairs(args[0], args[1][:1], args[2], [0], [1], [True], *tol)
    with pytest.raises(ValueError, match="kind"):
        kernel.CoalPairs([7, 1], *args[1:], [0], [1], [True], *tol)
    with pytest.raises(ValueError, match="no such body"):
        kernel.CoalPairs(*args, [0], [2], [True], *tol)
    with pytest.raises(ValueError, match="both bodies"):
        kernel.CoalPairs([0, 1], *args[1:], [0], [1], [True], *tol)
    pairs = kernel.CoalPairs(*args, [0, 0], [1, 1], [True, False], *tol)
    with pytest.raises(ValueError, match="not a pair with a box"):
        pairs.measure(1, np.eye(4), np.eye(4))
    with pytest.raises(ValueError, match="not a pair with a box"):
        pairs.measure(2, np.eye(4), np.eye(4))


def test_a_kernel_built_with_another_coal_is_refused() -> None:
    check_coal(kernel.COAL_VERSION)
    with pytest.raises(KernelError, match=r"built with coal 3\.0\.3, but coal 3\.1\.0"):
        check_coal("3.1.0", built="3.0.3")
