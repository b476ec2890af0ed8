"""The kernel's lower bound of a pair with a box (``CoalPairs.lower_bound``) and the cull.

* on seeded random poses the bound is at most coal's distance (less coal's GJK
  tolerance), for a box against a capsule (in either order), a sphere, another box (the
  other's containing capsule) and a capsule touching or entering it; it is coal's
  distance for a sphere apart from the box (the slabs' gap of a point is its distance),
  and above the containing capsule's distance on many poses (it can cull);
* with ``within`` finite, the scene lists every pair closer than ``within`` with the
  numbers of the full measure, bit for bit (random states of a PUMA set-up, and the
  recorded states of ``panda_pair_shelf``);
* on the recorded states of ``panda_pair_shelf``, fewer pairs with a box go to coal
  than the containing capsules alone would send (a pair with a box is listed by the
  measure within ``d_i`` exactly when coal measured it).
"""

from __future__ import annotations

import numpy as np
import pytest
from collision_setups import experiment
from test_coal_pairs import _random_pose
from test_collision_rows import PUMA, _random_state, needs_robots

from dualarm_qp._compiled import kernel
from dualarm_qp.control.rollout import rollout
from dualarm_qp.geometry import Box, Capsule, capsule_proximities, sphere
from dualarm_qp.geometry.bounds import bounding_capsule
from dualarm_qp.geometry.distance import EPA_TOLERANCE, GJK_TOLERANCE, coal_parts
from dualarm_qp.step.limits.collision import CollisionLimit
from dualarm_qp.step.state import DualArmState

#: Coal's distance may exceed the true one by its GJK tolerance (relative, distances of
#: a metre or two here) and rounding: the bound must not exceed it by more [m].
COAL_SLACK = 1e-9


def _coal_pair(a: Box | Capsule, b: Box | Capsule) -> kernel.CoalPairs:
    """The kernel's coal pair (a, b), with local poses of the shapes' own."""
    parts = [coal_parts(a), coal_parts(b)]
    return kernel.CoalPairs([p[0] for p in parts], np.array([p[1] for p in parts]),
                            np.concatenate([p[2] for p in parts]), [0], [1], [True],
                            GJK_TOLERANCE, EPA_TOLERANCE)


def _world_capsule(shape: Box | Capsule, F: np.ndarray) -> tuple[np.ndarray, np.ndarray,
                                                                  float]:
    """The shape's capsule (a box's containing one) placed by its frame ``F``."""
    a, b, r = bounding_capsule(shape)
    return F[:3, :3] @ a + F[:3, 3], F[:3, :3] @ b + F[:3, 3], r


def _bounds(pair: kernel.CoalPairs, shapes: tuple[Box | Capsule, Box | Capsule],
            F_a: np.ndarray, F_b: np.ndarray) -> tuple[float, float, float]:
    """(the kernel's bound, the containing capsules' distance, coal's distance) [m]."""
    ca, cb = _world_capsule(shapes[0], F_a), _world_capsule(shapes[1], F_b)
    bound = pair.lower_bound(0, F_a, F_b, *ca, *cb)
    capsules = capsule_proximities(ca[0][None], ca[1][None], [ca[2]], cb[0][None],
                                   cb[1][None], [cb[2]]).distance[0]
    return bound, float(capsules), pair.measure(0, F_a, F_b).distance


def _box(rng: np.random.Generator) -> Box:
    """A box of random sizes [m] posed at random in its frame."""
    return Box(rng.uniform(0.02, 0.6, 3), pose=_random_pose(rng, 0.05))


def _capsule(rng: np.random.Generator) -> Capsule:
    a = rng.normal(0.0, 0.05, 3)
    return Capsule(a, a + rng.normal(0.0, 0.2, 3), float(rng.uniform(0.01, 0.1)))


def _ball(rng: np.random.Generator) -> Capsule:
    return sphere(float(rng.uniform(0.01, 0.1)), rng.normal(0.0, 0.05, 3))


MAKERS = {"box": _box, "capsule": _capsule, "sphere": _ball}
CASES = [("box", "capsule"), ("capsule", "box"), ("box", "box"), ("box", "sphere"),
         ("sphere", "box")]


@pytest.mark.parametrize("kinds", CASES, ids=["-".join(c) for c in CASES])
def test_the_bound_is_below_coal_on_random_poses(kinds: tuple[str, str]) -> None:
    rng = np.random.default_rng(sum(map(len, kinds)) + 10 * CASES.index(kinds))
    tighter = apart = overlapping = 0
    for shapes_seen in range(60):
        shapes = (MAKERS[kinds[0]](rng), MAKERS[kinds[1]](rng))
        pair = _coal_pair(*shapes)
        for _ in range(25):
            spread = float(rng.choice([0.05, 0.2, 0.6]))
            F_a, F_b = _random_pose(rng, spread), _random_pose(rng, spread)
            bound, capsules, distance = _bounds(pair, shapes, F_a, F_b)
            assert bound <= distance + COAL_SLACK, (shapes_seen, bound, distance)
            assert capsules <= distance + COAL_SLACK
            if distance > 0.0:
                apart += 1
                tighter += bound > capsules + 1e-3
                if "sphere" in kinds:  # a point's gaps along the box's axes: exact
                    assert bound == pytest.approx(distance, abs=COAL_SLACK)
            else:
                overlapping += 1
                assert bound == -np.inf  # nothing certain when they may overlap
    assert overlapping > 20 and apart > 300
    assert tighter > apart // 3, (tighter, apart)


@pytest.mark.parametrize("offset", [-0.05, -1e-3, 0.0, 1e-9, 1e-3, 0.05])
@pytest.mark.parametrize("box_first", [True, False], ids=["box-capsule", "capsule-box"])
def test_a_capsule_touching_or_entering_a_box(offset: float, box_first: bool) -> None:
    """A capsule along the box's face normal, its near end ``offset`` beyond the face [m].

    Its axis is parallel to a box axis: the bound is the distance while they are apart,
    and -inf once they may overlap (it says nothing of the depth).
    """
    rng = np.random.default_rng(7)
    box = Box([0.3, 0.2, 0.1], pose=_random_pose(rng, 0.05))
    r = 0.04
    # The axis' ends in the box's own axes: the near one r + offset above the face
    # z = +0.05, over the face's inside, the far one 0.3 m farther up.
    ends = np.array([[0.1, -0.05, 0.05 + r + offset], [0.1, -0.05, 0.35 + r + offset]])
    F_box = _random_pose(rng, 0.2)
    # The capsule in a frame of its own, placed where the box's frame puts it.
    F_cap = _random_pose(rng, 0.2)
    to_cap = np.linalg.inv(F_cap) @ F_box @ box.pose
    a, b = ends @ to_cap[:3, :3].T + to_cap[:3, 3]
    capsule = Capsule(a, b, r)
    if box_first:
        bound, _, distance = _bounds(_coal_pair(box, capsule), (box, capsule), F_box, F_cap)
    else:
        bound, _, distance = _bounds(_coal_pair(capsule, box), (capsule, box), F_cap, F_box)
    assert distance == pytest.approx(offset, abs=1e-8)
    if offset > 1e-6:
        assert bound == pytest.approx(distance, abs=COAL_SLACK)
    else:
        assert bound <= distance + COAL_SLACK
    if offset < 0.0:
        assert bound == -np.inf


def test_the_bound_is_for_pairs_with_a_box() -> None:
    box = Box([0.3, 0.2, 0.1])
    capsule = Capsule([0, 0, 0], [0, 0, 0.2], 0.05)
    parts = [coal_parts(box), coal_parts(capsule)]
    pairs = kernel.CoalPairs([p[0] for p in parts], np.array([p[1] for p in parts]),
                             np.concatenate([p[2] for p in parts]), [0, 0], [1, 1],
                             [True, False], GJK_TOLERANCE, EPA_TOLERANCE)
    zero, one = np.zeros(3), np.ones(3)
    with pytest.raises(ValueError, match="not a pair with a box"):
        pairs.lower_bound(1, np.eye(4), np.eye(4), zero, one, 0.1, zero, one, 0.1)
    # Two capsules measured by coal: no box, nothing certain here.
    two = _coal_pair(capsule, capsule)
    assert two.lower_bound(0, np.eye(4), np.eye(4), zero, one, 0.1, 5 * one, 6 * one,
                           0.1) == -np.inf


# ---------------------------------------------------------------- the scene's cull
def _limit(exp):
    builder = exp.controller().builder
    return builder, next(lim for lim in builder.limits if isinstance(lim, CollisionLimit))


@pytest.fixture(scope="module")
def shelf():
    """The shelf's builder, collision limit and the states of its rollout."""
    exp = experiment("panda_pair_shelf", {})
    res = rollout(exp.controller(), exp.initial, duration=exp.duration, limits=exp.limits)
    assert res.completed
    tr = res.trace
    states = [DualArmState(float(tr.tau[k]), tr.q_l[k], tr.q_f[k], float(tr.grasp[k]))
              for k in range(len(tr))]
    builder, limit = _limit(exp)
    return builder, limit, states


def _within_keeps_the_close_pairs(scene, frames: np.ndarray, within: float) -> None:
    full = scene.measure(frames)
    part = scene.measure(frames, within)
    assert np.all(np.diff(part.pairs) > 0)
    where = {int(k): j for j, k in enumerate(part.pairs.tolist())}
    for k in np.flatnonzero(full.prox.distance < within).tolist():
        j = where[k]
        assert part.prox.distance[j] == full.prox.distance[k]
        for u, v in ((part.prox.point_a, full.prox.point_a),
                     (part.prox.point_b, full.prox.point_b),
                     (part.prox.normal, full.prox.normal)):
            np.testing.assert_array_equal(u[j], v[k])


@pytest.mark.parametrize("seed", range(4))
def test_within_keeps_every_close_pair_puma(seed: int) -> None:
    exp = experiment(*PUMA)
    builder, limit = _limit(exp)
    state = _random_state(exp, builder.layout, np.random.default_rng(seed))
    frames = limit.frames(builder.build(state).context)
    for within in (0.05, 0.3, 1.0):
        _within_keeps_the_close_pairs(limit.scene, frames, within)


@needs_robots
def test_within_keeps_every_close_pair_shelf(shelf) -> None:
    builder, limit, states = shelf
    for state in states[::5]:
        frames = limit.frames(builder.build(state).context)
        for within in (0.02, limit._d_i, 0.3):
            _within_keeps_the_close_pairs(limit.scene, frames, within)


@needs_robots
def test_fewer_shelf_pairs_go_to_coal(shelf) -> None:
    """Each step sends fewer pairs with a box to coal than their capsules would.

    Measured: 8.9 pairs a step by the containing capsules (of 15 pairs with a box),
    6.4 with the slabs' bound; the 6.4 are the pairs closer than ``d_i``.
    """
    builder, limit, states = shelf
    scene, d_i = limit.scene, limit._d_i
    boxed = np.array(scene._boxed)
    by_capsules = by_slabs = 0
    for state in states:
        frames = limit.frames(builder.build(state).context)
        capsules = kernel.scene_proximities(
            frames.reshape(-1, 4), scene._frame_list, scene._a, scene._b, scene._r,
            scene._sphere, scene._ia_list, scene._ib_list, d_i)  # no coal: capsules only
        before = int(np.count_nonzero(boxed[capsules.pairs] & (capsules.distance < d_i)))
        after = int(np.count_nonzero(boxed[scene.measure(frames, d_i).pairs]))
        assert after <= before
        by_capsules += before
        by_slabs += after
    assert by_slabs <= 0.8 * by_capsules, (by_slabs / len(states), by_capsules / len(states))
