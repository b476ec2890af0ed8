"""A pose from a position and roll-pitch-yaw angles or a rotation matrix.

:func:`pose` is the one reading of a pose in dualarm_qp: an experiment file's ``base``,
``tool``, ``H1`` and trajectory poses are built by it too, so the same numbers typed in
Python and written in a YAML file give the same matrix.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from ._validate import as_array
from .errors import InvalidInputError

FloatArray = NDArray[np.float64]

#: Length units a pose may be given in, and their size in metres.
LENGTH_UNITS = {"m": 1.0, "mm": 1e-3}

#: Angle units a pose may be given in, and their size in radians.
ANGLE_UNITS = {"rad": 1.0, "deg": math.pi / 180.0}

#: How far ``R^T R`` may be from the identity for a matrix to count as a rotation
#: (the tolerance of ``numpy.allclose`` with ``atol``; a rounded matrix is accepted, then
#: re-orthonormalised).
ROTATION_TOLERANCE = 1e-6


def pose(position: Any = (0.0, 0.0, 0.0), *, rpy: Any = None, rotation: Any = None,
         units: Mapping[str, str] | None = None) -> FloatArray:
    """Return the 4x4 homogeneous transform of a position and an orientation.

    This is the pose of an experiment file (``{position, rpy}`` or
    ``{position, rotation}``), read the same way: ``rpy = [roll, pitch, yaw]`` turns about
    the fixed x, y and z axes in that order, ``R = Rz(yaw) Ry(pitch) Rx(roll)``.

    Parameters
    ----------
    position : array_like, shape (3,)
        Origin of the frame [m, or the length unit of ``units``]; default the origin.
    rpy : array_like, shape (3,), optional, keyword-only
        Roll, pitch and yaw [rad, or the angle unit of ``units``].
    rotation : array_like, shape (3, 3), optional, keyword-only
        A proper rotation matrix (its columns are the frame's axes). It is checked to
        :data:`ROTATION_TOLERANCE` and re-orthonormalised, so rounded entries such as
        ``0.7071`` are accepted. Give ``rpy`` or ``rotation``, not both; with neither the
        orientation is the identity.
    units : mapping, optional, keyword-only
        The units of ``position`` and ``rpy``, as an experiment file's ``units`` block:
        ``{"length": "m" | "mm", "angle": "rad" | "deg"}``; a missing key is SI. Default:
        SI (m, rad).

    Returns
    -------
    ndarray, shape (4, 4)
        The transform, in SI: rotation block ``R``, translation [m], last row
        ``[0, 0, 0, 1]``. A new array.

    Raises
    ------
    ShapeError
        ``position`` or ``rpy`` is not three numbers, ``rotation`` not 3x3.
    NonFiniteError
        A value is NaN or infinite.
    InvalidInputError
        Both ``rpy`` and ``rotation`` are given, ``rotation`` is not a proper rotation,
        a value is not a number, or ``units`` has an unknown key or unit.

    Examples
    --------
    >>> import dualarm_qp as dq
    >>> T = dq.pose([1200, 0, 0], rpy=[0, 0, 180], units={"length": "mm", "angle": "deg"})
    >>> T[:3, 3].tolist()
    [1.2, 0.0, 0.0]
    >>> T[:3, 0].round(12).tolist()  # the frame's x axis points along world -x
    [-1.0, 0.0, 0.0]
    """
    length, angle = _unit_scales(units)
    if rpy is not None and rotation is not None:
        raise InvalidInputError("give either rpy or rotation, not both")
    p = as_array(position, "position", (3,)) * length
    if rotation is not None:
        R = as_array(rotation, "rotation", (3, 3))
        if not np.allclose(R.T @ R, np.eye(3), atol=ROTATION_TOLERANCE):
            gap = float(np.max(np.abs(R.T @ R - np.eye(3))))
            raise InvalidInputError(f"rotation must be a rotation matrix: R^T R is {gap:.3g} "
                                    f"away from the identity (allowed: {ROTATION_TOLERANCE:g})")
        if np.linalg.det(R) < 0.0:
            raise InvalidInputError("rotation must be a proper rotation matrix (determinant "
                                    "+1); this one is a reflection (determinant -1)")
        u, _, vt = np.linalg.svd(R)
        R = u @ vt
    elif rpy is not None:
        r, pitch, y = as_array(rpy, "rpy", (3,)) * angle
        R = pin.rpy.rpyToMatrix(r, pitch, y)  # Rz(y) Ry(pitch) Rx(r)
    else:
        R = np.eye(3)
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = p
    return T


def _unit_scales(units: Mapping[str, str] | None) -> tuple[float, float]:
    """Sizes of the length unit [m] and the angle unit [rad] of ``units``."""
    if units is None:
        return 1.0, 1.0
    if not isinstance(units, Mapping):
        raise InvalidInputError("units must be a mapping such as {'length': 'mm', 'angle': "
                                f"'deg'}}, got {type(units).__name__}")
    unknown = sorted(str(k) for k in units if k not in ("length", "angle"))
    if unknown:
        raise InvalidInputError(f"units: unknown key {', '.join(map(repr, unknown))} "
                                "(valid: length, angle)")
    length = units.get("length", "m")
    angle = units.get("angle", "rad")
    if not (isinstance(length, str) and length in LENGTH_UNITS):
        raise InvalidInputError(f"units: unknown length unit {length!r} "
                                f"(valid: {', '.join(LENGTH_UNITS)})")
    if not (isinstance(angle, str) and angle in ANGLE_UNITS):
        raise InvalidInputError(f"units: unknown angle unit {angle!r} "
                                f"(valid: {', '.join(ANGLE_UNITS)})")
    return LENGTH_UNITS[length], ANGLE_UNITS[angle]
