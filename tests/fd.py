"""Finite differences shared by the Jacobian tests."""

from __future__ import annotations

import numpy as np
import pinocchio as pin


def fd_jacobian(arm, q: np.ndarray, h: float = 1e-6) -> np.ndarray:
    """Central differences of ``arm.fk``: position, and log(R(q+h) R(q-h)^T) / 2h."""
    J = np.empty((6, arm.n))
    for i in range(arm.n):
        dq = np.zeros(arm.n)
        dq[i] = h
        Tp, Tm = arm.fk(q + dq), arm.fk(q - dq)
        J[:3, i] = (Tp[:3, 3] - Tm[:3, 3]) / (2 * h)
        J[3:, i] = pin.log3(Tp[:3, :3] @ Tm[:3, :3].T) / (2 * h)
    return J
