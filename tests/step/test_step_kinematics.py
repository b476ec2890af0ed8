"""Both arms' kinematics of one step in one compiled call, against the calls it replaces.

``both_arms`` must give what the carried-object model, the follower arm,
:func:`~dualarm_qp.se3.pose_error` and numpy's SVD give one call at a time: on the PUMA
pair with one sliding grasp (plane and curved bar), with both grasps sliding, and on a
UR5 pair; the kernel's pose error must equal the Python convention, also at rotations
near pi (where log3 changes branch).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from test_step_builder import make_task

from dualarm_qp import example_robot_arm
from dualarm_qp.se3 import pose_error
from dualarm_qp.step.kinematics import both_arms
from dualarm_qp.task.carry import CarryModel
from dualarm_qp.task.surfaces import CurvedBar, PlaneBar

seeds = st.integers(min_value=0, max_value=2**32 - 1)


def one_at_a_time(carry, follower, q_l, q_f, sigma, sigma_l, T_D):
    kin = carry.update(q_l, sigma, sigma_l)
    T_f, J_f = follower.fk_jacobian(q_f)
    sv = (np.linalg.svd(kin.J_tool, compute_uv=False)[-1],
          np.linalg.svd(J_f, compute_uv=False)[-1])
    return kin, T_f, J_f, pose_error(T_D, kin.T_object), pose_error(kin.T_target, T_f), sv


def assert_same_error(e, want):
    """The same pose error; within 1e-6 rad of pi (the sliding leader's grasp frame turns
    the follower's target by pi, so its closure error sits there) the rotation vector's
    sign is decided by rounding: the same rotation then."""
    np.testing.assert_allclose(e[:3], want[:3], rtol=0, atol=1e-12)
    if np.pi - np.linalg.norm(want[3:]) < 1e-6:
        np.testing.assert_allclose(pin.exp3(e[3:]), pin.exp3(want[3:]), rtol=0, atol=1e-6)
    else:
        np.testing.assert_allclose(e[3:], want[3:], rtol=0, atol=1e-12)


def assert_agree(carry, follower, q_l, q_f, sigma, sigma_l, T_D):
    got = both_arms(carry, follower, q_l, q_f, sigma, sigma_l, T_D)
    kin, T_f, J_f, e_l, e_c, sv = one_at_a_time(carry, follower, q_l, q_f, sigma, sigma_l,
                                                T_D)
    for name in ("T_tool", "J_tool", "T_object", "J_object", "T_target", "J_target"):
        np.testing.assert_allclose(getattr(got.carry, name), getattr(kin, name), rtol=0,
                                   atol=1e-13, err_msg=name)
    np.testing.assert_allclose(got.T_f, T_f, rtol=0, atol=1e-13)
    np.testing.assert_allclose(got.J_f, J_f, rtol=0, atol=1e-13)
    assert_same_error(got.leader_error, e_l)
    assert_same_error(got.closure_error, e_c)
    np.testing.assert_allclose(got.sigma_min, sv, rtol=1e-9, atol=1e-14)


@settings(max_examples=40, deadline=None)
@given(seeds, st.sampled_from(["plane", "curved", "both"]))
def test_the_puma_pair_agrees_with_the_calls_one_at_a_time(seed, kind):
    rng = np.random.default_rng(seed)
    surface = CurvedBar(0.5, sigma_max=0.3) if kind == "curved" else PlaneBar()
    task, q_l, q_f, sigma = make_task(rng, surface, identity_h1=kind == "both")
    lead = PlaneBar(r_min=(0, 0, -0.4), r_max=(0, 0, 0)) if kind == "both" else None
    carry = CarryModel(task.leader, task.surface, task.H1, lead)
    sigma_l = -0.2 if lead is not None else 0.0
    T_D = random_pose(rng)
    assert_agree(carry, task.follower, q_l, q_f, sigma, sigma_l, T_D)


def test_a_ur5_pair_agrees_with_the_calls_one_at_a_time():
    rng = np.random.default_rng(7)
    arm = example_robot_arm("ur5", root="base_link", tip="tool0")
    carry = CarryModel(arm, PlaneBar(), np.eye(4))
    for _ in range(10):
        q_l, q_f = rng.uniform(-2, 2, 6), rng.uniform(-2, 2, 6)
        assert_agree(carry, arm, q_l, q_f, 0.2, 0.0, random_pose(rng))


def random_pose(rng):
    """A pose drawn from ``rng`` (Pinocchio's own random draws are not seeded here)."""
    T = np.eye(4)
    T[:3, :3] = pin.exp3(rng.normal(size=3))
    T[:3, 3] = rng.normal(size=3)
    return T


@pytest.mark.parametrize("angle", [0.0, 1e-9, 1.0, 3.0, np.pi - 1e-4, np.pi - 1e-7, np.pi])
def test_the_pose_error_is_the_controllers_convention(angle):
    """The same vector; within 1e-6 rad of pi, where the axis's sign is decided by
    rounding (of two products computed differently), the same rotation."""
    rng = np.random.default_rng(3)
    for _ in range(50):
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        T = random_pose(rng)
        T_star = T.copy()
        T_star[:3, :3] = pin.exp3(angle * axis) @ T[:3, :3]
        T_star[:3, 3] += rng.normal(size=3)
        e = pose_error(T_star, T)  # the kernel's
        want = np.r_[T_star[:3, 3] - T[:3, 3], pin.log3(T_star[:3, :3] @ T[:3, :3].T)]
        np.testing.assert_allclose(e[:3], want[:3], rtol=0, atol=1e-14)
        if np.pi - angle < 1e-6:
            np.testing.assert_allclose(pin.exp3(e[3:]), pin.exp3(want[3:]), rtol=0, atol=1e-6)
            assert np.linalg.norm(e[3:]) == pytest.approx(angle, abs=1e-7)
        else:
            np.testing.assert_allclose(e[3:], want[3:], rtol=0, atol=1e-10)
