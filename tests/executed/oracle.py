"""An independent forward-kinematics oracle for the PUMA 560 (standard DH, Table 1).

Written from the table alone, with plain numpy 4x4 products; it shares no code with
``dualarm_qp.kinematics``. Lengths in m, angles in rad.
"""

from __future__ import annotations

import numpy as np

#: PUMA 560, Table 1: alpha [deg], a [mm], d [mm]; no joint offsets.
ALPHA = np.deg2rad([-90.0, 0.0, 90.0, -90.0, 90.0, 0.0])
A = np.array([0.0, 431.8, -20.32, 0.0, 0.0, 0.0]) / 1000.0
D = np.array([0.0, 149.09, 0.0, 433.07, 0.0, 56.25]) / 1000.0


def rot_z(theta: float) -> np.ndarray:
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]], dtype=float)


def rot_x(theta: float) -> np.ndarray:
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[1, 0, 0, 0], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1]], dtype=float)


def trans(x: float, y: float, z: float) -> np.ndarray:
    out = np.eye(4)
    out[:3, 3] = (x, y, z)
    return out


def puma_fk(q, base=None, tool=None) -> np.ndarray:
    """``base @ prod_i Rz(q_i) Tz(d_i) Tx(a_i) Rx(alpha_i) @ tool`` (4x4)."""
    q = np.asarray(q, dtype=float)
    assert q.shape == (6,), q.shape
    T = np.eye(4) if base is None else np.array(base, dtype=float)
    for i in range(6):
        T = T @ rot_z(q[i]) @ trans(0.0, 0.0, D[i]) @ trans(A[i], 0.0, 0.0) @ rot_x(ALPHA[i])
    if tool is not None:
        T = T @ np.array(tool, dtype=float)
    return T


def inv_pose(T) -> np.ndarray:
    """Inverse of a rigid transform."""
    T = np.asarray(T, dtype=float)
    out = np.eye(4)
    out[:3, :3] = T[:3, :3].T
    out[:3, 3] = -T[:3, :3].T @ T[:3, 3]
    return out


def is_puma(arm) -> bool:
    """Whether ``arm`` (a library SerialArm) carries the Table 1 parameters this oracle knows."""
    dh = arm.dh
    return (dh.convention == "standard" and dh.n == 6
            and np.allclose(dh.a, A, atol=1e-12, rtol=0)
            and np.allclose(dh.alpha, ALPHA, atol=1e-12, rtol=0)
            and np.allclose(dh.d, D, atol=1e-12, rtol=0)
            and np.allclose(dh.offset, 0.0, atol=0, rtol=0))
