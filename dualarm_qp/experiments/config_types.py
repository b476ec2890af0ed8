"""The value types of experiment files: numbers, flags, vectors, units and poses.

Shared by the schema of an experiment (:mod:`.config`) and of its scene
(:mod:`.config_scene`): every number is checked the same way (no booleans or text
read as numbers, no NaN, a bounded magnitude) and every model refuses unknown keys.
"""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal

import numpy as np
from pydantic import (
    AfterValidator,
    AllowInfNan,
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    model_validator,
)
from pydantic_core import PydanticCustomError


class Model(BaseModel):
    """A part of an experiment file: unknown keys are errors, values are frozen."""

    model_config = ConfigDict(extra="forbid", frozen=True)


def keyed(key: str, message: str) -> PydanticCustomError:
    """Return a validation error of a model-level check that belongs to one key.

    :func:`parse_config` appends ``key`` to the model's location, so the message names
    e.g. ``controller.dt`` rather than ``controller``.
    """
    return PydanticCustomError("keyed", "{message}", {"key": key, "message": message})


def _number(value: Any) -> Any:
    """Refuse what pydantic would otherwise turn into a number: booleans and text.

    ``dt: true`` would read as 1 and ``dt: "0.1"`` as 0.1; both are mistakes in a file.
    """
    if isinstance(value, bool):
        raise ValueError(f"must be a valid number, not {str(value).lower()}")
    if isinstance(value, (str, bytes)):
        raise ValueError("must be a valid number, not text")
    return value


def _not_nan(value: float) -> float:
    if math.isnan(value):
        raise ValueError("must be a number, not NaN")
    return value


#: Largest magnitude of a number in a file: beyond it (1e12 m, rad, s, ...) the
#: arithmetic of a run overflows long before it means anything.
MAX_MAGNITUDE = 1e12

#: A finite number (int or float; not a boolean, text, NaN or infinity), at most
#: :data:`MAX_MAGNITUDE` in size.
Num = Annotated[float, BeforeValidator(_number), AllowInfNan(False),
                Field(ge=-MAX_MAGNITUDE, le=MAX_MAGNITUDE)]
#: A number that may be infinite (a joint limit that does not limit); never NaN.
LimitNum = Annotated[float, BeforeValidator(_number), AfterValidator(_not_nan)]

#: A yes/no setting: only ``true`` or ``false`` (YAML 1.2), never ``yes``, ``on``, 1 or text.
Flag = Annotated[bool, Field(strict=True)]

Vec3 = Annotated[list[Num], Field(min_length=3, max_length=3)]


def _indicator(value: Any) -> Any:
    if isinstance(value, bool):
        raise ValueError(f"must be +1 or -1, not {str(value).lower()}")
    return value


Indicator = Annotated[Literal[1, -1], BeforeValidator(_indicator)]


def scalar_to_list(value: Any) -> Any:
    """Read a single value as a one-element list (before validation)."""
    return value if isinstance(value, (list, tuple)) else [value]


class Units(Model):
    """Units used by the numbers of this file."""

    length: Literal["m", "mm"] = "m"
    angle: Literal["rad", "deg"] = "rad"
    time: Literal["s", "ms"] = "s"


class PoseSpec(Model):
    """A pose: ``position`` plus either ``rpy`` or a 3x3 ``rotation`` matrix.

    ``rpy`` is roll, pitch, yaw about the fixed x, y, z axes: R = Rz(yaw) Ry(pitch) Rx(roll).
    """

    position: Vec3 = Field(default_factory=lambda: [0.0, 0.0, 0.0])
    rpy: Vec3 | None = None
    rotation: Annotated[list[Vec3], Field(min_length=3, max_length=3)] | None = None

    @model_validator(mode="after")
    def _one_rotation(self) -> PoseSpec:
        if self.rpy is not None and self.rotation is not None:
            raise keyed("rotation", "give either rpy or rotation, not both")
        if self.rotation is not None:
            R = np.asarray(self.rotation, dtype=float)
            if not np.allclose(R.T @ R, np.eye(3), atol=1e-6) or np.linalg.det(R) < 0:
                raise keyed("rotation", "must be a proper rotation matrix (orthonormal "
                             "to 1e-6, determinant +1)")
        return self


__all__ = ["MAX_MAGNITUDE", "Flag", "Indicator", "LimitNum", "Model", "Num", "PoseSpec",
           "Units", "Vec3", "keyed", "scalar_to_list"]
