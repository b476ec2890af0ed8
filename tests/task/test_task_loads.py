"""The load each hand carries (dualarm_qp.task.loads), against statics written here.

Every check is independent of the library's formulation: the balance is summed here
about a random common point with plain cross products; the minimum-norm split is solved
here from its KKT system; the frictionless slide is checked on the returned wrenches.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from dualarm_qp.errors import InvalidInputError, NonFiniteError
from dualarm_qp.task.loads import (
    ObjectLoad,
    UnbalancedLoadError,
    rigid_grasp,
    sliding_grasp,
    split_load,
    support_push,
    wrench_space,
)

finite = st.floats(-1.0, 1.0, allow_nan=False)
vec3 = st.tuples(finite, finite, finite).map(np.array)


def _rotation(q: np.ndarray) -> np.ndarray:
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


quats = st.tuples(finite, finite, finite, finite).map(np.array).filter(
    lambda q: np.linalg.norm(q) > 0.1)


def _pose(q: np.ndarray, p: np.ndarray) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = _rotation(q)
    T[:3, 3] = p
    return T


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)


def balance(points: list[np.ndarray], wrenches: np.ndarray, centre: np.ndarray,
            weight: np.ndarray, about: np.ndarray) -> np.ndarray:
    """Sum of the hands' wrenches and the weight's, about ``about``: [N; N m]."""
    force = weight.copy()
    moment = np.cross(centre - about, weight)
    for p, w in zip(points, wrenches, strict=True):
        force += w[:3]
        moment += w[3:] + np.cross(p - about, w[:3])
    return np.r_[force, moment]


@settings(max_examples=60, deadline=None)
@given(q=quats, p=vec3, rc=vec3, g=vec3, p1=vec3, p2=vec3, s=vec3, o=vec3,
       mass=st.floats(0.1, 50.0))
def test_rigid_and_sliding_grasp_balance_the_weight_and_the_slide_carries_nothing_along_it(
        q, p, rc, g, p1, p2, s, o, mass):
    """At random poses and grasps the split balances (to 1e-9) and the slide is frictionless."""
    assume(np.linalg.norm(g) > 0.1 and np.linalg.norm(s) > 0.1)
    assume(np.linalg.norm(p1 - p2) > 0.05)
    s = _unit(s)
    T = _pose(q, p)
    load = ObjectLoad(mass, rc, g * 9.81)
    split = split_load([rigid_grasp(p1), sliding_grasp(p2, s)], load, T)
    centre = T[:3, :3] @ rc + T[:3, 3]
    res = balance([p1, p2], split.wrenches, centre, mass * g * 9.81, about=o * 3.0)
    scale = load.weight * max(1.0, float(np.linalg.norm(o * 3.0 - centre)) + 3.0)
    assert np.max(np.abs(res)) <= 1e-9 * scale
    f_f, m_f = split.wrenches[1, :3], split.wrenches[1, 3:]
    # A frictionless slide: no force along the slide, no moment about its axis.
    assert abs(f_f @ s) <= 1e-9 * load.weight
    assert abs(m_f @ s) <= 1e-9 * load.weight * split.length
    assert split.internal == 4  # 6 + 4 unknowns, 6 equations


def test_a_load_along_the_slide_goes_to_the_rigid_hand_only():
    """Gravity along the sliding axis through both grasps: the slide carries nothing."""
    s = np.array([0.0, 0.0, 1.0])
    load = ObjectLoad(2.0, [0.0, 0.0, 0.3], [0.0, 0.0, -9.81])
    split = split_load([rigid_grasp([0, 0, 0]), sliding_grasp([0, 0, 0.5], s)], load,
                       np.eye(4))
    np.testing.assert_allclose(split.wrenches[1], 0.0, atol=1e-12)
    np.testing.assert_allclose(split.wrenches[0], [0, 0, 2 * 9.81, 0, 0, 0], atol=1e-12)


def test_the_symmetric_beam_is_shared_equally_without_moments():
    """Two rigid hands at the ends of a level beam, mass in the middle: half each."""
    load = ObjectLoad(4.0, [0.0, 0.0, 0.0], [0.0, 0.0, -10.0])
    split = split_load([rigid_grasp([-0.5, 0, 0]), rigid_grasp([0.5, 0, 0])], load,
                       np.eye(4))
    np.testing.assert_allclose(split.wrenches, [[0, 0, 20, 0, 0, 0]] * 2, atol=1e-12)


@pytest.mark.parametrize("c", [0.0, 0.25, 0.5, 0.8, 1.0])
def test_the_level_beam_of_the_docs(c):
    """docs/derivation.md: a rigid leader at 0, a slide along the beam at L, mass at c L.

    The follower carries ``M g (2 + c) / 5`` and each hand bends with ``M g L (1 - 2 c) / 5``
    (worked out by hand from the four unknowns a + b = M g, u + v = L b - c L M g).
    """
    L, Mg = 0.8, 10.0
    split = split_load([rigid_grasp([0, 0, 0]), sliding_grasp([L, 0, 0], [1, 0, 0])],
                       ObjectLoad(1.0, [c * L, 0, 0], [0, 0, -Mg]), np.eye(4))
    b, u = Mg * (2 + c) / 5, Mg * L * (1 - 2 * c) / 5
    np.testing.assert_allclose(split.wrenches, [[0, 0, Mg - b, 0, u, 0], [0, 0, b, 0, u, 0]],
                               atol=1e-12)


@settings(max_examples=40, deadline=None)
@given(q=quats, p=vec3, rc=vec3, p1=vec3, p2=vec3, s=vec3, k=vec3, z=st.lists(
    st.floats(-1.0, 1.0), min_size=4, max_size=4), mass=st.floats(0.1, 50.0))
def test_minimum_norm_rule_any_other_balancing_split_squeezes_more(q, p, rc, p1, p2, s, k, z,
                                                                   mass):
    """The split is the KKT minimiser, and adding any internal wrench raises its norm."""
    assume(np.linalg.norm(s) > 0.1 and np.linalg.norm(p1 - p2) > 0.05)
    s = _unit(s)
    k = k - (k @ s) * s  # a curved slide turns about an axis normal to s
    T = _pose(q, p)
    load = ObjectLoad(mass, rc, [0.0, 0.0, -9.81])
    split = split_load([rigid_grasp(p1), sliding_grasp(p2, s, k)], load, T)
    L = float(np.linalg.norm(p1 - p2))
    assert split.length == pytest.approx(L)
    # Independent: wrench spaces from the free twists, balance about p1, KKT solve.
    B_l = np.eye(6)
    free = np.array([np.r_[s, k], np.r_[np.zeros(3), s]]).T
    B_f = np.linalg.svd(free)[0][:, 2:]
    W = np.diag([1, 1, 1, 1 / L**2, 1 / L**2, 1 / L**2])

    def about_p1(pt: np.ndarray) -> np.ndarray:
        A = np.eye(6)
        r = pt - p1
        A[3:, :3] = np.array([[0, -r[2], r[1]], [r[2], 0, -r[0]], [-r[1], r[0], 0]])
        return A

    G = np.hstack([about_p1(p1) @ B_l, about_p1(p2) @ B_f])  # 6 x 10
    centre = T[:3, :3] @ rc + T[:3, 3]
    weight = mass * np.array([0.0, 0.0, -9.81])
    b = -np.r_[weight, np.cross(centre - p1, weight)]
    H = np.zeros((10, 10))
    H[:6, :6] = B_l.T @ W @ B_l
    H[6:, 6:] = B_f.T @ W @ B_f
    K = np.block([[H, G.T], [G, np.zeros((6, 6))]])
    lam = np.linalg.solve(K, np.r_[np.zeros(10), b])[:10]
    best = np.vstack([B_l @ lam[:6], B_f @ lam[6:]])
    np.testing.assert_allclose(split.wrenches, best, atol=1e-9 * load.weight * max(1.0, L))

    def squeeze(w: np.ndarray) -> float:
        return float(sum(x @ W @ x for x in w))

    N = np.linalg.svd(G)[2][6:].T  # internal wrenches: G N = 0
    dz = N @ np.array(z)  # any internal wrench, in the hands' coordinates
    other_lam = lam + dz
    other = np.vstack([B_l @ other_lam[:6], B_f @ other_lam[6:]])
    assert np.max(np.abs(G @ other_lam - b)) <= 1e-9 * load.weight * max(1.0, L)  # balances
    extra = squeeze(other) - squeeze(split.wrenches)
    internal = np.vstack([B_l @ dz[:6], B_f @ dz[6:]])
    assert extra == pytest.approx(squeeze(internal), rel=1e-6, abs=1e-9 * load.weight**2)
    if np.linalg.norm(z) > 1e-3:
        assert extra > 0.0


@settings(max_examples=40, deadline=None)
@given(q=quats, p=vec3, rc=vec3, p1=vec3, p2=vec3, a=vec3, h=st.floats(0.5, 200.0),
       mass=st.floats(0.1, 50.0), o=vec3)
def test_a_support_pushes_its_given_push_and_the_leader_takes_the_rest(q, p, rc, p1, p2, a, h,
                                                                        mass, o):
    assume(np.linalg.norm(a) > 0.1)
    a = _unit(a)
    T = _pose(q, p)
    load = ObjectLoad(mass, rc, [0.0, 0.0, -9.81])
    split = split_load([rigid_grasp(p1), support_push(p2, a, h)], load, T)
    np.testing.assert_allclose(split.wrenches[1], np.r_[h * a, 0, 0, 0], rtol=0, atol=1e-12)
    centre = T[:3, :3] @ rc + T[:3, 3]
    res = balance([p1, p2], split.wrenches, centre, mass * np.array([0, 0, -9.81]), o)
    assert np.max(np.abs(res)) <= 1e-9 * max(load.weight, h) * 5.0
    assert split.internal == 0


def test_two_slides_along_one_axis_cannot_hold_a_load_along_it():
    """Two frictionless grasps on one bar: gravity along the bar is refused, across it held."""
    s = np.array([0.0, 0.0, 1.0])
    hands = [sliding_grasp([0, 0, 0.1], s), sliding_grasp([0, 0, 0.6], s)]
    with pytest.raises(UnbalancedLoadError, match="cannot hold"):
        split_load(hands, ObjectLoad(1.0, [0, 0, 0.3], [0, 0, -9.81]), np.eye(4))
    # Across the bar, mass centre on the axis: held, shared by the lever rule.
    split = split_load(hands, ObjectLoad(1.0, [0, 0, 0.3], [-9.81, 0, 0]), np.eye(4))
    assert split.wrenches[0, 0] + split.wrenches[1, 0] == pytest.approx(9.81)
    assert abs(split.wrenches[:, 2]).max() < 1e-12  # nothing along the bar
    assert abs(split.wrenches[:, 5]).max() < 1e-12  # no moment about it
    # Mass centre off the axis: the bar would roll in the grasps.
    with pytest.raises(UnbalancedLoadError):
        split_load(hands, ObjectLoad(1.0, [0, 0.05, 0.3], [-9.81, 0, 0]), np.eye(4))


def test_wrench_spaces_have_the_stated_dimensions():
    assert wrench_space(rigid_grasp([0, 0, 0])).shape == (6, 6)
    B = wrench_space(sliding_grasp([0, 0, 0], [1, 1, 0]))
    assert B.shape == (6, 4)
    np.testing.assert_allclose(B.T @ B, np.eye(4), atol=1e-12)
    np.testing.assert_allclose(B[:3].T @ [1, 1, 0], 0.0, atol=1e-12)
    np.testing.assert_allclose(B[3:].T @ [1, 1, 0], 0.0, atol=1e-12)


@pytest.mark.parametrize(("kwargs", "word"), [
    ({"mass": -1.0}, "mass"), ({"mass": 0.0}, "mass"), ({"mass": float("nan")}, "mass"),
    ({"mass_centre": [0.0, 0.0]}, "mass_centre"), ({"gravity": [0.0, 0.0, 0.0]}, "gravity"),
    ({"gravity": [0.0, float("inf"), 0.0]}, "gravity"),
])
def test_bad_loads_are_refused_naming_the_value(kwargs, word):
    args = {"mass": 1.0, "mass_centre": [0.0, 0.0, 0.0], "gravity": [0.0, 0.0, -9.81]}
    with pytest.raises(InvalidInputError, match=word):
        ObjectLoad(**{**args, **kwargs})


@settings(max_examples=60, deadline=None)
@given(point=st.lists(st.floats(-10, 10), min_size=3, max_size=3),
       sliding=st.lists(st.floats(-1, 1), min_size=3, max_size=3).filter(
           lambda v: sum(x * x for x in v) > 1e-6),
       turn=st.lists(st.floats(-5, 5), min_size=3, max_size=3))
def test_the_per_step_grasps_equal_the_checked_ones(point, sliding, turn) -> None:
    """The statics a step makes without a second check equal the public grasps, bit for bit."""
    from dualarm_qp.task.loads import rigid_statics, sliding_statics

    p, s, k = (np.array(v, dtype=float) for v in (point, sliding, turn))
    checked, fast = sliding_grasp(p, s, k), sliding_statics(p, s, k)
    assert np.array_equal(checked.point, fast.point) and np.array_equal(checked.free, fast.free)
    assert fast.point is not p  # a copy: the caller's array may change
    assert np.array_equal(rigid_grasp(p).free, rigid_statics(p).free)
    # The public grasps still refuse what is not finite.
    with pytest.raises(NonFiniteError):
        sliding_grasp(p, s, [np.nan, 0.0, 0.0])
