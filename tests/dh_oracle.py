"""An independent Denavit-Hartenberg oracle: forward kinematics, link frames, Jacobian.

Written from the textbook formulas with plain numpy 4x4 products; it shares no code with
``dualarm_qp`` (which computes kinematics with Pinocchio). Rows are
``(a, alpha, d, offset)``; lengths in m, angles in rad.

standard: ``A_i = Rot_z(theta_i) Trans_z(d_i) Trans_x(a_i) Rot_x(alpha_i)``, joint i
turns about z of frame i-1. modified: ``A_i = Rot_x(alpha_{i-1}) Trans_x(a_{i-1})
Rot_z(theta_i) Trans_z(d_i)``, joint i turns about z of frame i.
"""

from __future__ import annotations

import numpy as np


def rot_z(theta: float) -> np.ndarray:
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]], dtype=float)


def rot_x(theta: float) -> np.ndarray:
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[1, 0, 0, 0], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1]], dtype=float)


def trans(x: float = 0.0, y: float = 0.0, z: float = 0.0) -> np.ndarray:
    out = np.eye(4)
    out[:3, 3] = (x, y, z)
    return out


def link(row: np.ndarray, q: float, convention: str) -> np.ndarray:
    """The link transform ``A_i`` of one DH row at joint angle ``q``."""
    a, alpha, d, offset = [*row, 0.0][:4]
    theta = q + offset
    if convention == "standard":
        return rot_z(theta) @ trans(z=d) @ trans(x=a) @ rot_x(alpha)
    if convention == "modified":
        return rot_x(alpha) @ trans(x=a) @ rot_z(theta) @ trans(z=d)
    raise ValueError(convention)


def frames(rows: np.ndarray, q: np.ndarray, convention: str,
           base: np.ndarray | None = None) -> np.ndarray:
    """World poses of DH frames 0..n, shape (n+1, 4, 4)."""
    T = np.eye(4) if base is None else np.array(base, dtype=float)
    out = [T]
    for row, qi in zip(rows, q, strict=True):
        T = T @ link(row, qi, convention)
        out.append(T)
    return np.array(out)


def fk(rows: np.ndarray, q: np.ndarray, convention: str, base: np.ndarray | None = None,
       tool: np.ndarray | None = None) -> np.ndarray:
    """``base @ A_1 ... A_n @ tool``."""
    T = frames(rows, q, convention, base)[-1]
    return T if tool is None else T @ np.asarray(tool, dtype=float)


def jacobian(rows: np.ndarray, q: np.ndarray, convention: str,
             base: np.ndarray | None = None, tool: np.ndarray | None = None) -> np.ndarray:
    """Geometric Jacobian, rows [v; w] of the tool origin in world coordinates (6, n).

    Column i is ``[z_i x (p_tool - o_i); z_i]`` for the axis z_i of joint i through a
    point o_i on it: frame i-1's z axis and origin (standard), or frame i's z axis and
    the point ``d_i`` back along it from frame i's origin (modified; that point is on the
    axis too, so frame i's origin works as well).
    """
    F = frames(rows, q, convention, base)
    p_tool = fk(rows, q, convention, base, tool)[:3, 3]
    axes = F[:-1] if convention == "standard" else F[1:]
    J = np.empty((6, len(q)))
    for i, A in enumerate(axes):
        z, o = A[:3, 2], A[:3, 3]
        J[:3, i] = np.cross(z, p_tool - o)
        J[3:, i] = z
    return J
