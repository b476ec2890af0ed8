"""An independent statics oracle for two hands holding one object (world frame, SI).

Written from rigid-body statics alone; it shares no code with ``dualarm_qp``. A wrench
is ``[f; m]``, the force [N] and moment [N m] a hand applies to the object, the moment
about the hand's grasp point.
"""

from __future__ import annotations

import numpy as np


def skew(v: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def residual(points: list[np.ndarray], wrenches: np.ndarray, centre: np.ndarray,
             weight: np.ndarray, about: np.ndarray) -> np.ndarray:
    """Sum of the hands' and the weight's wrenches about ``about`` (zero: balanced)."""
    force = weight + sum(w[:3] for w in wrenches)
    moment = np.cross(centre - about, weight) + sum(
        w[3:] + np.cross(p - about, w[:3]) for p, w in zip(points, wrenches, strict=True))
    return np.r_[force, moment]


def slide_space(s: np.ndarray) -> np.ndarray:
    """Wrenches of a frictionless straight slide along unit ``s``: f.s = 0, m.s = 0 (6x4)."""
    u = np.linalg.svd(s[:, None])[0][:, 1:]  # 3x2, normal to s
    out = np.zeros((6, 4))
    out[:3, :2] = u
    out[3:, 2:] = u
    return out


def min_norm_split(points: list[np.ndarray], spaces: list[np.ndarray], centre: np.ndarray,
                   weight: np.ndarray, length: float) -> np.ndarray:
    """The balancing wrenches of least ``sum |f|^2 + |m|^2 / length^2`` (KKT solve)."""
    W = np.diag([1.0, 1.0, 1.0, length**-2, length**-2, length**-2])
    o = points[0]
    cols, H_blocks = [], []
    for p, B in zip(points, spaces, strict=True):
        A = np.eye(6)
        A[3:, :3] = skew(p - o)
        cols.append(A @ B)
        H_blocks.append(B.T @ W @ B)
    G = np.hstack(cols)
    n = G.shape[1]
    H = np.zeros((n, n))
    start = 0
    for Hb in H_blocks:
        k = Hb.shape[0]
        H[start:start + k, start:start + k] = Hb
        start += k
    b = -np.r_[weight, np.cross(centre - o, weight)]
    K = np.block([[H, G.T], [G, np.zeros((6, 6))]])
    lam = np.linalg.solve(K, np.r_[np.zeros(n), b])[:n]
    out, start = [], 0
    for B in spaces:
        k = B.shape[1]
        out.append(B @ lam[start:start + k])
        start += k
    return np.array(out)
