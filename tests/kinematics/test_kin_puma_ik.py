"""Closed-form PUMA 560 inverse kinematics: every branch, indicators, limits, edge cases."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from dualarm_qp.errors import IKError, InvalidInputError
from dualarm_qp.kinematics import (
    DHTable,
    IKSolution,
    SerialArm,
    ik_branch,
    puma560,
    puma560_ik,
    puma560_indicators,
)
from dualarm_qp.se3 import pose_error

TOL = 1e-9  # [m] and [rad]


def random_pose(rng: np.random.Generator, scale: float = 1.0) -> np.ndarray:
    return pin.SE3(pin.exp3(rng.normal(size=3)), scale * rng.normal(size=3)).homogeneous


def assert_reaches(arm: SerialArm, sol: IKSolution, T: np.ndarray) -> None:
    e = pose_error(T, arm.fk(sol.q))
    assert np.linalg.norm(e[:3]) < TOL and np.linalg.norm(e[3:]) < TOL, e
    assert arm.within_limits(sol.q)
    assert puma560_indicators(arm, sol.q) == sol.indicators


@pytest.mark.slow  # the tests below check fewer poses in the fast loop
@pytest.mark.parametrize("placed", [False, True])
def test_round_trip_thousands_of_poses(placed: bool) -> None:
    rng = np.random.default_rng(11 + placed)
    arm = puma560(base=random_pose(rng), tool=random_pose(rng, 0.1)) if placed else puma560()
    counts = np.zeros(9, dtype=int)
    for _ in range(1500):
        q = rng.uniform(arm.q_min, arm.q_max)
        T = arm.fk(q)
        sols = puma560_ik(arm, T, q_ref=q)
        counts[len(sols)] += 1
        triples = [s.indicators for s in sols]
        assert len(set(triples)) == len(sols)  # one solution per distinct branch
        for s in sols:
            assert_reaches(arm, s, T)
        own = [s for s in sols if s.indicators == puma560_indicators(arm, q)]
        assert len(own) == 1
        np.testing.assert_allclose(own[0].q, q, atol=1e-8)  # the original branch, same q
    # Joint limits cut some branches, but 8 must occur and most poses have several.
    assert counts[8] > 0 and counts[0] == 0


def test_eight_branches_have_distinct_joints_and_indicators() -> None:
    arm = puma560()
    q = np.deg2rad([35.0, -30.0, 100.0, 150.0, 65.0, -265.0])
    sols = puma560_ik(arm, arm.fk(q))
    assert len(sols) == 8
    assert {s.indicators for s in sols} == {
        (a, e, w) for a in (1, -1) for e in (1, -1) for w in (1, -1)
    }
    qs = np.array([s.q for s in sols])
    dist = np.abs(qs[:, None, :] - qs[None, :, :]).max(axis=2)
    assert dist[~np.eye(8, dtype=bool)].min() > 1e-3


def test_indicator_meaning() -> None:
    """arm = +1: a positive joint-2 rate raises the wrist centre; elbow = +1: elbow above
    the shoulder-wrist line; wrist = sign(sin q5)."""
    arm = puma560()
    rng = np.random.default_rng(5)
    for _ in range(200):
        q = rng.uniform(arm.q_min, arm.q_max)
        a, e, w = puma560_indicators(arm, q)
        F = arm.link_frames(q)
        wrist_c = F[4][:3, 3]
        z1 = F[1][:3, 2]
        dz = np.cross(z1, wrist_c - F[1][:3, 3])[2]  # d(p_z)/d(q2) of the wrist centre
        if abs(dz) > 1e-6:
            assert a == (1 if dz > 0 else -1)
        shoulder = F[1][:3, 3] + 0.14909 * z1  # in the plane of joints 2 and 3
        elbow = F[2][:3, 3]
        d = wrist_c - shoulder
        t = d @ (elbow - shoulder) / (d @ d)
        height = (elbow - (shoulder + t * d))[2]
        if abs(height) > 1e-6 and abs(d[2]) < 0.9 * np.linalg.norm(d):
            assert e == (1 if height > 0 else -1)
        assert w == (1 if np.sin(q[4]) >= 0 else -1)


def test_ik_branch_returns_each_branch_or_raises() -> None:
    arm = puma560()
    rng = np.random.default_rng(2)
    raised = 0
    for _ in range(100):
        q = rng.uniform(arm.q_min, arm.q_max)
        T = arm.fk(q)
        found = {s.indicators: s for s in puma560_ik(arm, T, q_ref=q)}
        for triple in [(a, e, w) for a in (1, -1) for e in (1, -1) for w in (1, -1)]:
            if triple in found:
                sol = ik_branch(arm, T, *triple, q_ref=q)
                np.testing.assert_allclose(sol.q, found[triple].q, atol=1e-12)
            else:
                with pytest.raises(IKError, match="joint limits"):
                    ik_branch(arm, T, *triple, q_ref=q)
                raised += 1
    assert raised > 0


def test_unreachable_pose() -> None:
    arm = puma560()
    far = pin.SE3(np.eye(3), np.array([2.0, 0.0, 0.0])).homogeneous
    assert puma560_ik(arm, far) == []
    with pytest.raises(IKError, match="out of reach"):
        ik_branch(arm, far, 1, 1, 1)
    # Inside the cylinder of radius d2 around the z0 axis: unreachable too.
    inner = pin.SE3(np.eye(3), np.array([0.0, 0.05, 0.2 + 0.05625])).homogeneous
    assert puma560_ik(arm, inner) == []


def test_wrist_singularity_keeps_q4_from_reference() -> None:
    """With q5 = 0 joints 4 and 6 align: q4 stays at the reference, one wrist branch."""
    arm = puma560()
    q = np.deg2rad([20.0, -40.0, 100.0, 35.0, 0.0, -50.0])
    T = arm.fk(q)
    arm_elbow = puma560_indicators(arm, q)[:2]
    for q4_ref in (0.0, 0.3, -1.0):
        ref = q.copy()
        ref[3] = q4_ref
        sols = puma560_ik(arm, T, q_ref=ref)
        for s in sols:
            assert_reaches(arm, s, T)
        singular = [s for s in sols if s.indicators[:2] == arm_elbow]
        assert len(singular) == 1  # both wrist branches coincide
        assert singular[0].q[3] == pytest.approx(q4_ref)
        assert abs(singular[0].q[4]) < 1e-9
        for wrist in (1, -1):  # asking for either wrist branch gives that solution
            np.testing.assert_allclose(ik_branch(arm, T, *arm_elbow, wrist, q_ref=ref).q,
                                       singular[0].q, atol=0)


@pytest.mark.parametrize("q5", [1e-4, 1e-7, 1e-9, 1e-11, 1e-13])
def test_accurate_near_the_wrist_singularity(q5: float) -> None:
    arm = puma560()
    rng = np.random.default_rng(9)
    for _ in range(50):
        q = rng.uniform(arm.q_min, arm.q_max)
        q[4] = q5 * rng.choice([-1.0, 1.0])
        T = arm.fk(q)
        sols = puma560_ik(arm, T, q_ref=q)
        assert sols
        for s in sols:
            assert_reaches(arm, s, T)


def test_joint6_representative_closest_to_reference() -> None:
    arm = puma560()
    q = np.deg2rad([0.0, -45.0, 90.0, 10.0, 30.0, 200.0])
    T = arm.fk(q)
    same = [s for s in puma560_ik(arm, T, q_ref=q) if np.allclose(s.q[:5], q[:5])]
    assert same and same[0].q[5] == pytest.approx(q[5])
    near_zero = [s for s in puma560_ik(arm, T) if np.allclose(s.q[:5], q[:5])]
    assert near_zero[0].q[5] == pytest.approx(q[5] - 2 * np.pi)


def test_solution_is_immutable() -> None:
    arm = puma560()
    sol = puma560_ik(arm, arm.fk(np.full(6, 0.2)))[0]
    with pytest.raises(ValueError):
        sol.q[0] = 1.0


def test_rejects_non_puma_arm_and_bad_inputs() -> None:
    arm = puma560()
    T = arm.fk(np.zeros(6))
    other = SerialArm(DHTable.from_rows(np.ones((6, 3))))
    with pytest.raises(InvalidInputError, match="PUMA"):
        puma560_ik(other, T)
    with pytest.raises(InvalidInputError):
        puma560_indicators(other, np.zeros(6))
    with pytest.raises(InvalidInputError):
        puma560_ik(arm, np.eye(3))
    with pytest.raises(InvalidInputError):
        puma560_ik(arm, T, q_ref=np.zeros(5))
    bad = T.copy()
    bad[:3, :3] *= 2.0
    with pytest.raises(InvalidInputError):
        puma560_ik(arm, bad)
    with pytest.raises(InvalidInputError):
        ik_branch(arm, T, 0, 1, 1)
    with pytest.raises(InvalidInputError):
        puma560_ik("puma", T)  # type: ignore[arg-type]
