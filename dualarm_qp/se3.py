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
    return np.array(_log_rows(R.tolist()))


def rotation_error(R_target: FloatArray, R_actual: FloatArray) -> FloatArray:
    """World-frame rotation vector taking ``R_actual`` to ``R_target`` [rad].

    ``exp_so3(e) @ R_actual == R_target``; to first order ``e`` is the angular
    displacement the actual frame must make.
    """
    return np.array(_log_rows(_mul_transposed(*R_target.tolist(), *R_actual.tolist())))


def pose_error(T_target: FloatArray, T_actual: FloatArray) -> FloatArray:
    """6-vector ``[dp; dw]``: position error [m] and world rotation error [rad]."""
    return np.array(pose_error_rows(T_target.tolist(), T_actual.tolist()))


#: A matrix as nested Python lists, row by row (what ``ndarray.tolist()`` returns).
Rows = list[list[float]]


def pose_error_rows(target: Rows, actual: Rows) -> list[float]:
    """:func:`pose_error` on the rows of two poses (3x4 or 4x4), as six Python floats.

    Scalar math: for one 4x4 pose numpy's per-call overhead costs more than the
    arithmetic. Used by the per-step code, which keeps its small matrices as lists.
    """
    a0, a1, a2 = target[0], target[1], target[2]
    b0, b1, b2 = actual[0], actual[1], actual[2]
    return [a0[3] - b0[3], a1[3] - b1[3], a2[3] - b2[3],
            *_log_rows(_mul_transposed(a0, a1, a2, b0, b1, b2))]


def compose_rows(a: Rows, b: Rows) -> Rows:
    """Rows 0-2 of the pose ``A B``, for poses given by their rows (3x4 or 4x4) [m]."""
    b00, b01, b02, b03 = b[0][0], b[0][1], b[0][2], b[0][3]
    b10, b11, b12, b13 = b[1][0], b[1][1], b[1][2], b[1][3]
    b20, b21, b22, b23 = b[2][0], b[2][1], b[2][2], b[2][3]
    out = []
    for r0, r1, r2, r3 in (a[0], a[1], a[2]):
        out.append([r0 * b00 + r1 * b10 + r2 * b20, r0 * b01 + r1 * b11 + r2 * b21,
                    r0 * b02 + r1 * b12 + r2 * b22, r0 * b03 + r1 * b13 + r2 * b23 + r3])
    return out


def _mul_transposed(a0: list[float], a1: list[float], a2: list[float],
                    b0: list[float], b1: list[float], b2: list[float]) -> Rows:
    """Rows of ``A B^T`` for the 3x3 blocks of ``A`` and ``B`` given by their rows."""
    out = []
    for x in (a0, a1, a2):
        x0, x1, x2 = x[0], x[1], x[2]
        out.append([x0 * b0[0] + x1 * b0[1] + x2 * b0[2], x0 * b1[0] + x1 * b1[1] + x2 * b1[2],
                    x0 * b2[0] + x1 * b2[1] + x2 * b2[2]])
    return out


def _log_rows(r: Rows) -> list[float]:
    """:func:`log_so3` of the rotation with rows ``r``, as three Python floats."""
    r0, r1, r2 = r[0], r[1], r[2]
    cos_theta = max(-1.0, min(1.0, 0.5 * (r0[0] + r1[1] + r2[2] - 1.0)))
    v0, v1, v2 = r2[1] - r1[2], r0[2] - r2[0], r1[0] - r0[1]  # vee(R - R^T)
    sin_theta = 0.5 * math.sqrt(v0 * v0 + v1 * v1 + v2 * v2)
    theta = math.atan2(sin_theta, cos_theta)
    if theta < 1e-6:
        k = 0.5 * (1.0 + theta**2 / 6.0)
        return [k * v0, k * v1, k * v2]
    if math.pi - theta > 1e-4:
        k = theta / (2.0 * math.sin(theta))
        return [k * v0, k * v1, k * v2]
    # Near pi: R = 2 u u^T - I + O(pi - theta); take the largest column of (R + I)/2.
    diag = (r0[0], r1[1], r2[2])
    i = max(range(3), key=diag.__getitem__)  # first of equal maxima, as np.argmax
    b_ii = 0.5 * (diag[i] + 1.0)
    u = [0.5 * (row[i] + (1.0 if j == i else 0.0)) for j, row in enumerate((r0, r1, r2))]
    s = math.sqrt(max(b_ii, 1e-300))
    u = [ui / s for ui in u]
    norm = math.sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2])
    if u[0] * v0 + u[1] * v1 + u[2] * v2 < 0.0:
        norm = -norm
    return [theta * u[0] / norm, theta * u[1] / norm, theta * u[2] / norm]


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
