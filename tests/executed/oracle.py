"""The PUMA 560 of Table 1 on the tests' independent DH oracle (``tests/dh_oracle.py``).

Written from the table alone; it shares no code with ``dualarm_qp.kinematics``.
Lengths in m, angles in rad.
"""

from __future__ import annotations

import dh_oracle
import numpy as np

#: PUMA 560, Table 1: alpha [deg], a [mm], d [mm]; no joint offsets.
ALPHA = np.deg2rad([-90.0, 0.0, 90.0, -90.0, 90.0, 0.0])
A = np.array([0.0, 431.8, -20.32, 0.0, 0.0, 0.0]) / 1000.0
D = np.array([0.0, 149.09, 0.0, 433.07, 0.0, 56.25]) / 1000.0


#: The table as oracle rows ``(a, alpha, d, offset)``.
ROWS = np.column_stack([A, ALPHA, D, np.zeros(6)])


def puma_fk(q, base=None, tool=None) -> np.ndarray:
    """``base @ prod_i Rz(q_i) Tz(d_i) Tx(a_i) Rx(alpha_i) @ tool`` (4x4)."""
    q = np.asarray(q, dtype=float)
    assert q.shape == (6,), q.shape
    return dh_oracle.fk(ROWS, q, "standard", base, tool)


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
