"""SO(3)/SE(3) maps from Pinocchio and our pose-error helpers: group axioms, near pi.

The rotations near pi are built from an independent Rodrigues formula with the
complement ``eps = pi - theta`` (``cos theta = -cos eps``, ``sin theta = sin eps``), so
they are exact to rounding even for ``eps = 1e-12``.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

from dualarm_qp.se3 import pose_error


def unit(rng: np.random.Generator) -> np.ndarray:
    u = rng.normal(size=3)
    return u / np.linalg.norm(u)


def rodrigues_near_pi(u: np.ndarray, eps: float) -> np.ndarray:
    """Rotation by ``pi - eps`` about the unit axis ``u``."""
    c, s = -math.cos(eps), math.sin(eps)
    return c * np.eye(3) + s * pin.skew(u) + (1.0 - c) * np.outer(u, u)


def random_pose(rng: np.random.Generator) -> np.ndarray:
    return pin.SE3(pin.exp3(rng.normal(size=3) * 2.0), rng.normal(size=3)).homogeneous


@pytest.mark.parametrize("k", range(1, 13))
def test_log_near_pi_round_trips(k: int) -> None:
    rng = np.random.default_rng(k)
    eps = 10.0**-k
    for _ in range(50):
        u = unit(rng)
        R = rodrigues_near_pi(u, eps)
        w = pin.log3(R)
        np.testing.assert_allclose(w, (math.pi - eps) * u, rtol=0, atol=1e-10)
        np.testing.assert_allclose(pin.exp3(w), R, rtol=0, atol=1e-10)
        # Our pose errors read the same rotation vector, in the world frame.
        A = random_pose(rng)
        B = A.copy()
        B[:3, :3] = R.T @ A[:3, :3]  # R_target = R R_actual
        np.testing.assert_allclose(pose_error(A, B)[3:], w, rtol=0, atol=1e-10)


def test_log_at_pi_is_a_rotation_by_pi() -> None:
    rng = np.random.default_rng(0)
    for _ in range(50):
        u = unit(rng)
        R = 2.0 * np.outer(u, u) - np.eye(3)
        w = pin.log3(R)
        assert np.linalg.norm(w) == pytest.approx(math.pi, abs=1e-12)
        np.testing.assert_allclose(pin.exp3(w), R, rtol=0, atol=1e-12)
        assert abs(abs(w @ u) - math.pi) < 1e-10  # +-pi u: both are the same rotation


def test_log_of_exp_is_identity_inside_the_ball_of_radius_pi() -> None:
    rng = np.random.default_rng(1)
    angles = [0.0, 1e-12, 1e-8, 1e-4, 0.5, 1.0, 2.0, 3.0, math.pi - 1e-3, math.pi - 1e-9]
    for angle in [*angles, *rng.uniform(0.0, math.pi, size=200)]:
        w = angle * unit(rng)
        np.testing.assert_allclose(pin.log3(pin.exp3(w)), w, rtol=0, atol=1e-10)


def test_exp_of_log_is_identity_on_so3() -> None:
    rng = np.random.default_rng(2)
    for _ in range(200):
        q = rng.normal(size=4)
        R = pin.Quaternion(*(q / np.linalg.norm(q))).matrix()
        np.testing.assert_allclose(pin.exp3(pin.log3(R)), R, rtol=0, atol=1e-10)
        assert np.linalg.norm(pin.log3(R)) <= math.pi + 1e-12


def test_exp_is_a_homomorphism_along_one_axis_and_inverse_is_transpose() -> None:
    rng = np.random.default_rng(3)
    for _ in range(100):
        u, a, b = unit(rng), *rng.uniform(-3.0, 3.0, size=2)
        np.testing.assert_allclose(pin.exp3(a * u) @ pin.exp3(b * u), pin.exp3((a + b) * u),
                                   rtol=0, atol=1e-12)
        np.testing.assert_allclose(pin.exp3(-a * u), pin.exp3(a * u).T, rtol=0, atol=1e-14)


def test_se3_composition_and_inverse_match_matrices() -> None:
    rng = np.random.default_rng(4)
    for _ in range(100):
        A, B, C = random_pose(rng), random_pose(rng), random_pose(rng)
        sA, sB, sC = pin.SE3(A), pin.SE3(B), pin.SE3(C)
        np.testing.assert_allclose((sA * sB).homogeneous, A @ B, rtol=0, atol=1e-12)
        np.testing.assert_allclose(((sA * sB) * sC).homogeneous, (sA * (sB * sC)).homogeneous,
                                   rtol=0, atol=1e-12)
        np.testing.assert_allclose(sA.inverse().homogeneous, np.linalg.inv(A),
                                   rtol=0, atol=1e-12)
        np.testing.assert_allclose((sA * sA.inverse()).homogeneous, np.eye(4),
                                   rtol=0, atol=1e-12)
        np.testing.assert_allclose(pin.exp6(pin.log6(sA)).homogeneous, A, rtol=0, atol=1e-10)


def test_pose_error_convention() -> None:
    """``[p* - p; dw]`` with ``exp3(dw) R == R*``: the world-frame rotation error."""
    rng = np.random.default_rng(5)
    for _ in range(100):
        target, actual = random_pose(rng), random_pose(rng)
        e = pose_error(target, actual)
        np.testing.assert_allclose(e[:3], target[:3, 3] - actual[:3, 3], rtol=0, atol=1e-15)
        np.testing.assert_allclose(pin.exp3(e[3:]) @ actual[:3, :3], target[:3, :3],
                                   rtol=0, atol=1e-12)
