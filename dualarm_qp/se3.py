"""SO(3) and SE(3) helpers: rotations, log maps, pose errors and twist transforms.

Conventions: a pose is a 4x4 homogeneous matrix ``T_a_b`` that maps coordinates in
frame b to frame a. A twist is a 6-vector ``[v; w]``: linear velocity [m/s] of a
stated point, then angular velocity [rad/s]. Orientation errors are rotation vectors
(axis times angle) [rad] expressed in the world frame.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


def skew(v: FloatArray) -> FloatArray:
    """Return the 3x3 matrix ``[v]x`` with ``[v]x @ u == np.cross(v, u)``."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def rot_x(angle: float) -> FloatArray:
    """Rotation about x by ``angle`` [rad]."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_y(angle: float) -> FloatArray:
    """Rotation about y by ``angle`` [rad]."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rot_z(angle: float) -> FloatArray:
    """Rotation about z by ``angle`` [rad]."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def make_pose(R: FloatArray | None = None, p: FloatArray | None = None) -> FloatArray:
    """Build a 4x4 pose from a rotation matrix and a translation [m]."""
    T = np.eye(4)
    if R is not None:
        T[:3, :3] = R
    if p is not None:
        T[:3, 3] = p
    return T


def inv_pose(T: FloatArray) -> FloatArray:
    """Inverse of a homogeneous transform, using the rotation's transpose."""
    Ti = np.eye(4)
    Rt = T[:3, :3].T
    Ti[:3, :3] = Rt
    Ti[:3, 3] = -Rt @ T[:3, 3]
    return Ti


def exp_so3(w: FloatArray) -> FloatArray:
    """Rotation matrix of the rotation vector ``w`` (axis times angle [rad])."""
    theta = math.sqrt(float(w @ w))
    K = skew(w)
    if theta < 1e-8:
        return np.eye(3) + K + 0.5 * K @ K
    return (
        np.eye(3)
        + (math.sin(theta) / theta) * K
        + ((1.0 - math.cos(theta)) / theta**2) * K @ K
    )


def log_so3(R: FloatArray) -> FloatArray:
    """Rotation vector ``w`` with ``exp_so3(w) == R``, angle in [0, pi] [rad].

    Accurate near zero and near pi (where the axis is read off the symmetric part).
    """
    cos_theta = max(-1.0, min(1.0, 0.5 * (R[0, 0] + R[1, 1] + R[2, 2] - 1.0)))
    vee = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    sin_theta = 0.5 * math.sqrt(float(vee @ vee))
    theta = math.atan2(sin_theta, cos_theta)
    if theta < 1e-6:
        return 0.5 * (1.0 + theta**2 / 6.0) * vee
    if math.pi - theta > 1e-4:
        return (theta / (2.0 * math.sin(theta))) * vee
    # Near pi: R = 2 u u^T - I + O(pi - theta); take the largest column of (R + I)/2.
    B = 0.5 * (R + np.eye(3))
    i = int(np.argmax(np.diag(B)))
    u = B[:, i] / math.sqrt(max(B[i, i], 1e-300))
    u /= np.linalg.norm(u)
    if float(u @ vee) < 0.0:
        u = -u
    return theta * u


def rotation_error(R_target: FloatArray, R_actual: FloatArray) -> FloatArray:
    """World-frame rotation vector taking ``R_actual`` to ``R_target`` [rad].

    ``exp_so3(e) @ R_actual == R_target``; to first order ``e`` is the angular
    displacement the actual frame must make.
    """
    return log_so3(R_target @ R_actual.T)


def pose_error(T_target: FloatArray, T_actual: FloatArray) -> FloatArray:
    """6-vector ``[dp; dw]``: position error [m] and world rotation error [rad]."""
    e = np.empty(6)
    e[:3] = T_target[:3, 3] - T_actual[:3, 3]
    e[3:] = rotation_error(T_target[:3, :3], T_actual[:3, :3])
    return e


def log_se3(T: FloatArray) -> FloatArray:
    """Twist coordinates ``[v; w]`` with ``expm([[w]x, v], [0, 0]]) == T``."""
    w = log_so3(T[:3, :3])
    theta = math.sqrt(float(w @ w))
    W = skew(w)
    if theta < 1e-8:
        V_inv = np.eye(3) - 0.5 * W + W @ W / 12.0
    else:
        half = 0.5 * theta
        coef = (1.0 - half * math.cos(half) / math.sin(half)) / theta**2
        V_inv = np.eye(3) - 0.5 * W + coef * W @ W
    out = np.empty(6)
    out[:3] = V_inv @ T[:3, 3]
    out[3:] = w
    return out


def exp_se3(xi: FloatArray) -> FloatArray:
    """Inverse of :func:`log_se3`."""
    v, w = xi[:3], xi[3:]
    theta = math.sqrt(float(w @ w))
    W = skew(w)
    R = exp_so3(w)
    if theta < 1e-8:
        V = np.eye(3) + 0.5 * W + W @ W / 6.0
    else:
        V = (
            np.eye(3)
            + ((1.0 - math.cos(theta)) / theta**2) * W
            + ((theta - math.sin(theta)) / theta**3) * W @ W
        )
    return make_pose(R, V @ v)


def shift_twist(twist: FloatArray, r: FloatArray) -> FloatArray:
    """Move the reference point of a twist by ``r`` [m] (world coordinates).

    Given ``[v_a; w]`` at point a, return ``[v_a + w x r; w]``, the twist at
    point ``a + r``.
    """
    out = twist.copy()
    w = twist[3:]
    out[:3] += np.array(
        [w[1] * r[2] - w[2] * r[1], w[2] * r[0] - w[0] * r[2], w[0] * r[1] - w[1] * r[0]]
    )
    return out


def rotate_twist(R: FloatArray, twist: FloatArray) -> FloatArray:
    """Express a twist given in frame b in frame a, with ``R = R_a_b``."""
    out = np.empty(6)
    out[:3] = R @ twist[:3]
    out[3:] = R @ twist[3:]
    return out


def adjoint(T: FloatArray) -> FloatArray:
    """6x6 adjoint of ``T`` for twists ordered ``[v; w]``.

    Maps a body twist in frame b (velocity of b's origin, in b) to a spatial twist in
    frame a: ``V_a = adjoint(T_a_b) @ V_b``.
    """
    R, p = T[:3, :3], T[:3, 3]
    A = np.zeros((6, 6))
    A[:3, :3] = R
    A[3:, 3:] = R
    A[:3, 3:] = skew(p) @ R
    return A
