"""What the simulator measures: each hand's wrench on the object and its internal part.

A hand's wrench on the object is read from its weld's constraint force
(``efc_force``), mapped through the weld's Jacobian onto the object's free joint: the
six generalised forces there are the force [N] in the world frame and the moment [N m]
about the object's origin in the object frame. They are returned as in
:mod:`dualarm_qp.task.loads`: ``[f; m]`` in the world frame, the moment about the
hand's grasp point.

The **internal** (squeeze) part of the two wrenches is what the hands push or twist
against each other without moving the object: the measured pair (each wrench first
projected onto what its grasp can transmit) minus the minimum-norm pair with the same
resultant, in the metric of the load split (``|f|^2 + |m|^2 / L^2``, ``L`` the distance
between the grasp points; :func:`dualarm_qp.task.loads.split_load`). Its size is the
larger of the two hands' internal forces [N].
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from ..task.loads import FALLBACK_LENGTH, wrench_space

FloatArray = NDArray[np.float64]

#: MuJoCo's constraint type of an equality (``mjCNSTR_EQUALITY``).
_EQUALITY = 0


def weld_wrench(model: Any, data: Any, eq: int, obj: int, dof: int, point: FloatArray
                ) -> FloatArray:
    """Return the wrench ``[f; m]`` equality ``eq`` applies to the object (world frame).

    Parameters
    ----------
    model, data
        MuJoCo's model and data after a step (dense constraint Jacobian).
    eq : int
        Index of the weld.
    obj : int
        Body index of the object; ``dof``: the first dof of its free joint.
    point : ndarray, shape (3,)
        The grasp point the moment is taken about [m], world.
    """
    nefc = int(data.nefc)
    rows = np.flatnonzero((data.efc_type[:nefc] == _EQUALITY) & (data.efc_id[:nefc] == eq))
    if rows.size == 0:
        return np.zeros(6)
    J = np.asarray(data.efc_J[:nefc * model.nv]).reshape(nefc, model.nv)[rows]
    gen = J[:, dof:dof + 6].T @ data.efc_force[rows]
    R = data.xmat[obj].reshape(3, 3)
    f = gen[:3]
    m_origin = R @ gen[3:]  # about the object's origin, world frame
    m = m_origin + np.cross(data.xpos[obj] - point, f)
    return np.r_[f, m]


def internal_force(points: tuple[FloatArray, FloatArray], spaces: tuple[FloatArray, FloatArray],
                   wrenches: tuple[FloatArray, FloatArray]) -> tuple[float, FloatArray]:
    """Return the size of the internal force [N] and the internal wrench pair (2, 6).

    Parameters
    ----------
    points : pair of ndarray, shape (3,)
        Grasp points [m], world (the leader's first).
    spaces : pair of ndarray, shape (6, k)
        What each grasp can transmit (:func:`~dualarm_qp.task.loads.wrench_space`).
    wrenches : pair of ndarray, shape (6,)
        Measured ``[f; m]`` about each grasp point [N, N m], world.
    """
    gap = float(np.linalg.norm(points[0] - points[1]))
    L = gap if gap > 1e-9 else FALLBACK_LENGTH
    S = np.diag([1.0, 1.0, 1.0, L, L, L])
    S_inv = np.diag([1.0, 1.0, 1.0, 1.0 / L, 1.0 / L, 1.0 / L])
    blocks, coords, bases = [], [], []
    for p, B, w in zip(points, spaces, wrenches, strict=True):
        C, _ = np.linalg.qr(S_inv @ B)
        A = np.eye(6)
        A[3:, :3] = pin.skew(p - points[0])
        blocks.append(S_inv @ A @ S @ C)
        coords.append(C.T @ (S_inv @ w))
        bases.append(C)
    G = np.hstack(blocks)
    mu = np.concatenate(coords)
    mu_int = mu - np.linalg.pinv(G, rcond=1e-10) @ (G @ mu)
    out = np.zeros((2, 6))
    start = 0
    for i, C in enumerate(bases):
        k = C.shape[1]
        out[i] = S @ C @ mu_int[start:start + k]
        start += k
    size = float(max(np.linalg.norm(out[0, :3]), np.linalg.norm(out[1, :3])))
    return size, out


def space_of(free: FloatArray) -> FloatArray:
    """Return the wrench space (6, 6 - k) of a grasp with free twists ``free`` (6, k)."""
    from ..task.loads import GraspStatics

    return wrench_space(GraspStatics(np.zeros(3), free))


__all__ = ["internal_force", "space_of", "weld_wrench"]
