"""Input checks shared by the public API: shapes, finiteness and limits."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .errors import InvalidInputError, LimitsError, NonFiniteError, ShapeError

FloatArray = NDArray[np.float64]


def as_array(value: Any, name: str, shape: tuple[int, ...]) -> FloatArray:
    """Return ``value`` as a finite float64 array of the given shape.

    Parameters
    ----------
    value : array_like
        The input.
    name : str
        Argument name used in error messages.
    shape : tuple of int
        Expected shape; ``-1`` accepts any length on that axis.

    Raises
    ------
    ShapeError
        Wrong number of dimensions or wrong length on an axis.
    NonFiniteError
        NaN or infinity in the input.
    InvalidInputError
        The input cannot be converted to floats.
    """
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as err:
        raise InvalidInputError(f"{name} must be an array of numbers: {err}") from err
    except OverflowError as err:  # an integer beyond the largest float
        raise NonFiniteError(name) from err
    if arr.ndim != len(shape) or any(
        s not in (-1, g) for s, g in zip(shape, arr.shape, strict=True)
    ):
        raise ShapeError(name, shape, arr.shape)
    if not np.all(np.isfinite(arr)):
        raise NonFiniteError(name)
    return arr


def as_pose(value: Any, name: str) -> FloatArray:
    """Return ``value`` as a 4x4 homogeneous transform, checking its rotation block.

    Raises
    ------
    InvalidInputError
        The rotation block is not orthonormal with determinant +1 (tolerance 1e-6)
        or the last row is not [0, 0, 0, 1].
    """
    T = as_array(value, name, (4, 4))
    R = T[:3, :3]
    if not np.allclose(T[3], (0.0, 0.0, 0.0, 1.0), atol=1e-9):
        raise InvalidInputError(f"{name} must have last row [0, 0, 0, 1], got {T[3]}")
    if not np.allclose(R.T @ R, np.eye(3), atol=1e-6) or np.linalg.det(R) < 0:
        raise InvalidInputError(f"{name} must have a proper rotation block (orthonormal, det +1)")
    return T


def as_number(value: Any, name: str) -> float:
    """Return ``value`` as a finite Python float.

    Raises
    ------
    InvalidInputError
        ``value`` is not a real number.
    NonFiniteError
        ``value`` is NaN or infinite.
    """
    try:
        number = float(value)
    except (TypeError, ValueError) as err:
        raise InvalidInputError(f"{name} must be a real number, got {value!r}") from err
    except OverflowError as err:  # an integer beyond the largest float
        raise NonFiniteError(name) from err
    if not math.isfinite(number):
        raise NonFiniteError(name)
    return number


def check_limits(lower: FloatArray, upper: FloatArray, name: str) -> None:
    """Raise :class:`LimitsError` where ``lower > upper``."""
    bad = np.flatnonzero(lower > upper)
    if bad.size:
        i = int(bad[0])
        raise LimitsError(
            f"{name}: lower limit {lower[i]:g} exceeds upper limit {upper[i]:g} at index {i}"
        )


def limit_array(value: Any, name: str, n: int) -> FloatArray:
    """Return ``n`` per-joint limits: infinite allowed, not NaN; a scalar is broadcast."""
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError, OverflowError) as err:
        raise InvalidInputError(f"{name} must be numbers: {err}") from err
    if arr.ndim == 0:
        arr = np.full(n, float(arr))
    if arr.shape != (n,):
        raise ShapeError(name, (n,), arr.shape)
    if np.isnan(arr).any():
        raise NonFiniteError(name)
    return arr
