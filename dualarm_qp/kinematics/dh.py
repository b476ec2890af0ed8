"""Denavit-Hartenberg tables (:class:`DHTable`) and the Pinocchio chain of one.

DH conventions, both for revolute joints:

``standard`` (Denavit-Hartenberg; Fu, Gonzalez and Lee)
    ``A_i = Rot_z(theta_i) Trans_z(d_i) Trans_x(a_i) Rot_x(alpha_i)``; joint i turns
    about the z axis of frame i-1.
``modified`` (Craig)
    ``A_i = Rot_x(alpha_{i-1}) Trans_x(a_{i-1}) Rot_z(theta_i) Trans_z(d_i)``; joint i
    turns about the z axis of frame i. Row i of the table holds
    ``(a_{i-1}, alpha_{i-1}, d_i, offset_i)``.

with ``theta_i = q_i + offset_i``. The pose of the tool in the world is
``T_world_tool = base @ A_1 ... A_n @ tool``.

Both are built as one Pinocchio chain: ``A_i = pre_i Rot_z(theta_i) post_i`` with
``pre = I, post = Trans_z(d) Trans_x(a) Rot_x(alpha)`` (standard) or
``pre = Rot_x(alpha) Trans_x(a), post = Trans_z(d)`` (modified). Joint i is a revolute
joint about its local z axis placed at ``post_{i-1} pre_i Rot_z(offset_i)`` in joint
i-1 (``post_0 = I``), and DH frame i is a frame at ``post_i`` on joint i.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from .._validate import as_array
from ..errors import InvalidInputError, ShapeError
from .chain import BASE_FRAME, LINK_FRAME, rot, se3, trans

FloatArray = NDArray[np.float64]
Convention = Literal["standard", "modified"]


@dataclass(frozen=True)
class DHTable:
    """Denavit-Hartenberg parameters, one row per joint (all revolute).

    Parameters
    ----------
    a : ndarray, shape (n,)
        Link lengths [m] (``a_i`` standard, ``a_{i-1}`` modified).
    alpha : ndarray, shape (n,)
        Link twists [rad] (``alpha_i`` standard, ``alpha_{i-1}`` modified).
    d : ndarray, shape (n,)
        Link offsets along z [m].
    offset : ndarray, shape (n,)
        Joint angle offsets [rad]: ``theta_i = q_i + offset_i``.
    convention : {"standard", "modified"}
        Which DH convention the rows follow.
    """

    a: FloatArray
    alpha: FloatArray
    d: FloatArray
    offset: FloatArray
    convention: Convention = "standard"

    def __post_init__(self) -> None:
        a = as_array(self.a, "a", (-1,))
        n = a.shape[0]
        if n == 0:
            raise InvalidInputError("a DH table needs at least one joint")
        for name in ("a", "alpha", "d", "offset"):
            # Own read-only copies: SerialArm caches these values.
            arr = as_array(getattr(self, name), name, (n,)).copy()
            arr.flags.writeable = False
            object.__setattr__(self, name, arr)
        if self.convention not in ("standard", "modified"):
            raise InvalidInputError(
                f"convention must be 'standard' or 'modified', got {self.convention!r}"
            )

    @classmethod
    def from_rows(cls, rows: Any, convention: Convention = "standard") -> DHTable:
        """Build from an (n, 3) or (n, 4) array of rows ``(a, alpha, d[, offset])``.

        Units: [m, rad, m, rad].

        Raises
        ------
        ShapeError, NonFiniteError, InvalidInputError
            Rows that are not an (n, 3) or (n, 4) array of finite numbers.
        """
        arr = as_array(rows, "DH rows", (-1, -1))  # numeric, finite, two-dimensional
        if arr.shape[1] not in (3, 4):
            raise ShapeError("DH rows", (-1, 4), tuple(arr.shape))
        offset = arr[:, 3] if arr.shape[1] == 4 else np.zeros(arr.shape[0])
        return cls(arr[:, 0], arr[:, 1], arr[:, 2], offset, convention)

    @property
    def n(self) -> int:
        """Number of joints."""
        return int(self.a.shape[0])


def dh_model(dh: DHTable) -> tuple[Any, list[int], int]:
    """Pinocchio chain of a DH table (see the module docstring).

    Returns the model (universe = DH frame 0), the ids of its frames 0..n and the id of
    the flange frame (frame n).
    """
    model = pin.Model()
    model.name = f"dh_{dh.convention}"
    links = [model.addFrame(pin.Frame(BASE_FRAME, 0, 0, pin.SE3.Identity(),
                                      pin.FrameType.OP_FRAME))]
    standard = dh.convention == "standard"
    post_prev = np.eye(4)
    for i in range(dh.n):
        a, alpha, d, offset = (float(dh.a[i]), float(dh.alpha[i]), float(dh.d[i]),
                               float(dh.offset[i]))
        # Trans_x(a) Rot_x(alpha)
        x_step = trans(a, 0.0, 0.0) @ rot(pin.rpy.rpyToMatrix(alpha, 0.0, 0.0))
        pre, post = (np.eye(4), trans(0.0, 0.0, d) @ x_step) if standard else (
            x_step, trans(0.0, 0.0, d))
        placement = post_prev @ pre @ rot(pin.rpy.rpyToMatrix(0.0, 0.0, offset))
        joint = model.addJoint(model.njoints - 1, pin.JointModelRZ(),
                               se3(placement), f"joint{i + 1}")
        links.append(model.addFrame(pin.Frame(f"{LINK_FRAME}{i + 1}", joint, links[-1],
                                              se3(post), pin.FrameType.OP_FRAME)))
        post_prev = post
    return model, links, links[-1]


__all__ = ["Convention", "DHTable", "dh_model"]
