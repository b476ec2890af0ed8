"""Reading an experiment file's values: units to SI, poses, vectors, and errors naming keys.

What every part of the set-up (:mod:`.setup`) reads the file with: the file's units as
factors to SI (:class:`Scales`), a pose, a vector of one value per joint, and
:func:`at_key`, which reports a library refusal as a ConfigError naming the key.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any, TypeVar

import numpy as np
from numpy.typing import NDArray

from ..errors import ConfigError, DualArmError
from ..poses import pose
from .config import ANGLE_SCALE, LENGTH_SCALE, TIME_SCALE, ExperimentConfig, PoseSpec

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class Scales:
    """File units to SI: multiply a file number by these."""

    length: float
    angle: float
    time: float

    @classmethod
    def of(cls, cfg: ExperimentConfig) -> Scales:
        """Return the factors of the file's ``units``."""
        return cls(LENGTH_SCALE[cfg.units.length], ANGLE_SCALE[cfg.units.angle],
                   TIME_SCALE[cfg.units.time])


def file_pose(spec: PoseSpec, sc: Scales) -> FloatArray:
    """Return the file's pose in SI, read by :func:`~dualarm_qp.poses.pose` as in Python."""
    return pose(np.asarray(spec.position, dtype=float) * sc.length,
                rpy=None if spec.rpy is None else np.asarray(spec.rpy, dtype=float) * sc.angle,
                rotation=spec.rotation)


T = TypeVar("T")


def required(value: T | None, key: str, path: str | None = None) -> T:
    """Return ``value``, which the schema guarantees; a clear error if it is missing anyway."""
    if value is None:
        raise ConfigError("missing required key", path=path, key=key)
    return value


def vector(values: list[float] | None, scale: float, n: int, key: str, path: str) -> Any:
    """Return the file's ``n`` values at ``key`` times ``scale`` (None when not given), checked.

    Every value must be finite, except in a limit (``q_min``, ..., ``tau_max``),
    where an infinity means none; never NaN.
    """
    if values is None:
        return None
    if len(values) != n:
        raise ConfigError(f"needs {n} values, got {len(values)}", path=path, key=key)
    arr = np.asarray(values, dtype=float) * scale
    if not np.isfinite(arr).all() and not key.endswith(("q_min", "q_max", "qd_max",
                                                        "qdd_max", "tau_max")):
        raise ConfigError("values must be finite numbers", path=path, key=key)
    if np.isnan(arr).any():
        raise ConfigError("values must not be NaN", path=path, key=key)
    return arr


@contextlib.contextmanager
def at_key(key: str, path: str) -> Iterator[None]:
    """Report a library refusal inside the block as a ConfigError naming ``key``."""
    try:
        yield
    except ConfigError:
        raise
    except DualArmError as err:
        raise ConfigError(str(err), path=path, key=key) from None


__all__ = ["Scales", "at_key", "file_pose", "required", "vector"]
