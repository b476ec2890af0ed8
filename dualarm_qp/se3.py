"""The controller's pose-error convention.

Everything else of SO(3)/SE(3) (exp/log maps, skew, inverses, roll-pitch-yaw) comes from
Pinocchio: ``pinocchio.exp3``/``log3``, ``pinocchio.SE3``, ``pinocchio.skew``,
``pinocchio.rpy.rpyToMatrix``.

Conventions: a pose is a 4x4 homogeneous matrix ``T_a_b`` that maps coordinates in
frame b to frame a. The error of a pose ``T`` to a target ``T*`` is the 6-vector
``[p* - p; log3(R* R^T)]`` [m; rad]: the rotation vector is in the world frame, and
``exp3(dw) R == R*``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ._compiled import kernel

FloatArray = NDArray[np.float64]


def pose_error(T_target: FloatArray, T_actual: FloatArray) -> FloatArray:
    """6-vector ``[dp; dw]``: position error [m] and world rotation error [rad].

    Computed by the compiled kernel (Pinocchio's C++ ``log3``), the one implementation
    of the convention, which the step's kinematics call also uses. The poses are 4x4.
    """
    e = np.empty(6)
    kernel.pose_error(T_target, T_actual, e)
    return e
