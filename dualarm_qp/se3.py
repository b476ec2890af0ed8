"""The controller's pose-error convention, and the plain-float pose helpers of the step.

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

#: A matrix as nested Python lists, row by row (what ``ndarray.tolist()`` returns).
Rows = list[list[float]]


def pose_error(T_target: FloatArray, T_actual: FloatArray) -> FloatArray:
    """6-vector ``[dp; dw]``: position error [m] and world rotation error [rad].

    Computed by the compiled kernel (Pinocchio's C++ ``log3``), the one implementation
    of the convention, which the step's kinematics call also uses. The poses are 4x4.
    """
    e = np.empty(6)
    kernel.pose_error(T_target, T_actual, e)
    return e


def compose_rows(a: Rows, b: Rows) -> Rows:
    """Rows 0-2 of the pose ``A B``, for poses given by their rows (3x4 or 4x4) [m].

    Plain floats: about twice as fast as ``pinocchio.SE3`` products with the
    conversions to and from lists that the step would need.
    """
    b00, b01, b02, b03 = b[0][0], b[0][1], b[0][2], b[0][3]
    b10, b11, b12, b13 = b[1][0], b[1][1], b[1][2], b[1][3]
    b20, b21, b22, b23 = b[2][0], b[2][1], b[2][2], b[2][3]
    out = []
    for r0, r1, r2, r3 in (a[0], a[1], a[2]):
        out.append([r0 * b00 + r1 * b10 + r2 * b20, r0 * b01 + r1 * b11 + r2 * b21,
                    r0 * b02 + r1 * b12 + r2 * b22, r0 * b03 + r1 * b13 + r2 * b23 + r3])
    return out

