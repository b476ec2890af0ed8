"""Experiment configuration files (YAML), validated and converted to SI on load.

Lengths in a file may be given in mm or m and angles in degrees or radians, as the
file's ``units`` block says; everything is converted to SI (m, rad, s) here, at the
boundary, and the library never sees file units. Unknown or misspelled keys are
errors that name the file, the key and the valid keys.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
import yaml
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from ..errors import ConfigError

FloatArray = NDArray[np.float64]

LENGTH_SCALE = {"m": 1.0, "mm": 1e-3}
ANGLE_SCALE = {"rad": 1.0, "deg": math.pi / 180.0}
TIME_SCALE = {"s": 1.0, "ms": 1e-3}


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


def _finite(values: list[float]) -> list[float]:
    for v in values:
        if not math.isfinite(v):
            raise ValueError("values must be finite numbers")
    return values


Vec3 = Annotated[list[float], Field(min_length=3, max_length=3)]


class Units(_Model):
    """Units used by the numbers of this file."""

    length: Literal["m", "mm"] = "m"
    angle: Literal["rad", "deg"] = "rad"
    time: Literal["s", "ms"] = "s"


class PoseSpec(_Model):
    """A pose: ``position`` plus either ``rpy`` or a 3x3 ``rotation`` matrix.

    ``rpy`` is roll, pitch, yaw about the fixed x, y, z axes: R = Rz(yaw) Ry(pitch) Rx(roll).
    """

    position: Vec3 = Field(default_factory=lambda: [0.0, 0.0, 0.0])
    rpy: Vec3 | None = None
    rotation: list[Vec3] | None = None

    @field_validator("position", "rpy")
    @classmethod
    def _check_finite(cls, v: list[float] | None) -> list[float] | None:
        return None if v is None else _finite(v)

    @model_validator(mode="after")
    def _one_rotation(self) -> PoseSpec:
        if self.rpy is not None and self.rotation is not None:
            raise ValueError("give either rpy or rotation, not both")
        if self.rotation is not None:
            R = np.asarray(self.rotation, dtype=float)
            if R.shape != (3, 3) or not np.isfinite(R).all():
                raise ValueError("rotation must be a 3x3 matrix of finite numbers")
            if not np.allclose(R.T @ R, np.eye(3), atol=1e-6) or np.linalg.det(R) < 0:
                raise ValueError("rotation must be a proper rotation matrix")
        return self


class DHSpec(_Model):
    """A DH table: rows ``[a, alpha, d]`` or ``[a, alpha, d, offset]``."""

    convention: Literal["standard", "modified"] = "standard"
    rows: list[list[float]] = Field(min_length=1)

    @field_validator("rows")
    @classmethod
    def _rows(cls, rows: list[list[float]]) -> list[list[float]]:
        widths = {len(r) for r in rows}
        if len(widths) != 1 or widths.pop() not in (3, 4):
            raise ValueError("every DH row must have 3 or 4 numbers [a, alpha, d(, offset)]")
        for r in rows:
            _finite(r)
        return rows


class IKBranch(_Model):
    """Closed-form IK branch indicators (+1 / -1) for the PUMA 560."""

    arm: Literal[1, -1] = 1
    elbow: Literal[1, -1] = 1
    wrist: Literal[1, -1] = 1


class InitialSpec(_Model):
    """Initial joints: given directly, or by an IK branch at D(t0)."""

    joints: list[float] | None = None
    ik_branch: IKBranch | None = None

    @model_validator(mode="after")
    def _one(self) -> InitialSpec:
        if (self.joints is None) == (self.ik_branch is None):
            raise ValueError("give exactly one of 'joints' or 'ik_branch'")
        return self


class ArmSpec(_Model):
    """One arm: a preset or a DH table, its base pose, limits and initial joints."""

    preset: Literal["puma560"] | None = None
    dh: DHSpec | None = None
    base: PoseSpec | Literal["auto"] = Field(default_factory=PoseSpec)
    tool: PoseSpec | None = None
    q_min: list[float] | None = None
    q_max: list[float] | None = None
    qd_max: list[float] | None = None
    initial: InitialSpec

    @model_validator(mode="after")
    def _one_model(self) -> ArmSpec:
        if (self.preset is None) == (self.dh is None):
            raise ValueError("give exactly one of 'preset' or 'dh'")
        return self


class SurfaceSpec(_Model):
    """The object surface and the follower's sliding path on it.

    ``plane_bar`` (the paper's bar): the grasp slides along object z on the plane x = 0,
    inside the box ``r_min``..``r_max`` (Eq. 3). ``cylinder`` (radius, azimuth) and
    ``curved_bar`` (radius of the arc, ``side``) take the grasp range ``grasp_range``
    (arc length along the path).
    """

    type: Literal["plane_bar", "cylinder", "curved_bar"] = "plane_bar"
    r_min: Vec3 | None = None
    r_max: Vec3 | None = None
    radius: float | None = None
    azimuth: float | None = None
    side: Literal["outer", "inner"] | None = None
    grasp_range: Annotated[list[float], Field(min_length=2, max_length=2)] | None = None

    @model_validator(mode="after")
    def _fields(self) -> SurfaceSpec:
        if self.type == "plane_bar":
            extra = [k for k in ("radius", "azimuth", "side", "grasp_range")
                     if getattr(self, k) is not None]
            if extra:
                raise ValueError(f"a plane_bar takes r_min and r_max, not {', '.join(extra)}")
        else:
            if self.radius is None or not (math.isfinite(self.radius) and self.radius > 0):
                raise ValueError(f"a {self.type} needs a positive 'radius'")
            if self.grasp_range is None:
                raise ValueError(f"a {self.type} needs 'grasp_range: [min, max]'")
            if self.r_min is not None or self.r_max is not None:
                raise ValueError(f"a {self.type} takes grasp_range, not r_min / r_max")
            if self.type == "cylinder" and self.side is not None:
                raise ValueError("'side' is for a curved_bar")
            if self.type == "curved_bar" and self.azimuth is not None:
                raise ValueError("'azimuth' is for a cylinder")
        return self


class ObjectSpec(_Model):
    """The carried object."""

    H1: PoseSpec = Field(default_factory=PoseSpec)
    surface: SurfaceSpec = Field(default_factory=SurfaceSpec)
    grasp_initial: float


class Waypoint(_Model):
    """One waypoint of the object path."""

    t: float
    pose: PoseSpec


class TrajectorySpec(_Model):
    """The desired object path D(t) in the world."""

    type: Literal["linear", "waypoints"] = "linear"
    start: PoseSpec | None = None
    velocity: Vec3 | None = None
    waypoints: list[Waypoint] | None = None

    @model_validator(mode="after")
    def _fields(self) -> TrajectorySpec:
        if self.type == "linear" and (self.start is None or self.velocity is None):
            raise ValueError("a linear trajectory needs 'start' and 'velocity'")
        if self.type == "waypoints" and (not self.waypoints or len(self.waypoints) < 2):
            raise ValueError("a waypoints trajectory needs at least two 'waypoints'")
        return self


class WeightsSpec(_Model):
    """Diagonal of S (Eq. 37).

    ``joints`` weighs follower joint rates in (rad/s)^-2 whatever the file's angle unit;
    ``grasp`` (the paper's s7) weighs the sliding speed in (grasp_unit / s)^-2, where
    ``grasp_unit`` defaults to the file's length unit: ``grasp: 100`` with
    ``grasp_unit: mm`` is 1e8 in SI, with ``grasp_unit: m`` it is 100.
    """

    joints: float | list[float] = 1.0
    grasp: float = 1.0
    grasp_unit: Literal["m", "mm"] | None = None

    @model_validator(mode="after")
    def _positive(self) -> WeightsSpec:
        joints = self.joints if isinstance(self.joints, list) else [self.joints]
        if not all(math.isfinite(w) and w > 0 for w in [*joints, self.grasp]):
            raise ValueError("weights must be finite and > 0")
        return self


class ControllerSpec(_Model):
    """Sampling, limits, weights and gains of the controller.

    ``correction_gain`` and ``leader_gain`` are in 1/(time unit), default ``1/dt``;
    ``centre_horizon`` (time unit, default ``dt``, the paper's) is how fast the range
    centres pull; ``projection`` turns the rollout's position-level drift correction
    after each step on or off (default: on for the paper's methods, which ignore
    limits; refused for a hard-limit solver); ``closure_tolerance`` and
    ``tracking_tolerance`` (``[length, angle]``, default 1 mm and 0.01 rad) fail a run
    whose grasp closure or leader tracking error exceeds them;
    ``singular_value_min`` (default 1e-3, SI) and ``singularity_action`` (warn, stop
    or ignore) say what a Jacobian near a singularity does; ``duration_cap`` (time
    unit, default twice ``duration``) is how long a slowed task may run.
    """

    dt: float
    duration: float
    weights: WeightsSpec = Field(default_factory=WeightsSpec)
    velocity_limits: bool = True
    grasp_speed_max: float | None = None
    correction_gain: float | None = None
    leader_gain: float | None = None
    centre_horizon: float | None = None
    recovery_fraction: float = 0.0
    policy: Literal["scale", "relax", "stop"] = "scale"
    exact_orientation: bool = False
    projection: bool | None = None
    closure_tolerance: Annotated[list[float], Field(min_length=2, max_length=2)] | None = None
    tracking_tolerance: Annotated[list[float], Field(min_length=2, max_length=2)] | None = None
    singular_value_min: float = 1e-3
    singularity_action: Literal["warn", "stop", "ignore"] = "warn"
    duration_cap: float | None = None

    @field_validator("singular_value_min")
    @classmethod
    def _non_negative_value(cls, v: float) -> float:
        if not (math.isfinite(v) and v >= 0):
            raise ValueError("must be a finite number >= 0")
        return v

    @model_validator(mode="after")
    def _cap(self) -> ControllerSpec:
        if self.duration_cap is not None and self.duration_cap < self.duration:
            raise ValueError(f"duration_cap ({self.duration_cap:g}) must be at least "
                             f"the duration ({self.duration:g})")
        return self

    @field_validator("dt", "duration", "centre_horizon", "grasp_speed_max", "duration_cap")
    @classmethod
    def _positive_time(cls, v: float | None) -> float | None:
        if v is not None and not (math.isfinite(v) and v > 0):
            raise ValueError("must be a positive number")
        return v

    @field_validator("correction_gain", "leader_gain")
    @classmethod
    def _non_negative(cls, v: float | None) -> float | None:
        if v is not None and not (math.isfinite(v) and v >= 0):
            raise ValueError("must be a finite number >= 0")
        return v

    @field_validator("recovery_fraction")
    @classmethod
    def _fraction(cls, v: float) -> float:
        if not 0 <= v <= 1:
            raise ValueError("must be in [0, 1]")
        return v

    @field_validator("closure_tolerance", "tracking_tolerance")
    @classmethod
    def _tolerance(cls, v: list[float] | None) -> list[float] | None:
        if v is not None and not all(math.isfinite(x) and x > 0 for x in v):
            raise ValueError("must be two positive numbers [length, angle]")
        return v


class SolverSpec(_Model):
    """Which solver from the registry, with its options.

    ``fallback`` names the solver that takes a step on which a hard-limit solver fails
    although the step is feasible (default ``nullspace``, the exact solver; ``none``
    lets such a step fail the run).
    """

    name: str = "reference"
    options: dict[str, Any] = Field(default_factory=dict)
    fallback: str = "nullspace"


class ExperimentConfig(_Model):
    """A whole experiment file (the values as written, in the file's units)."""

    name: str = "experiment"
    description: str = ""
    units: Units = Field(default_factory=Units)
    leader: ArmSpec
    follower: ArmSpec
    object: ObjectSpec
    trajectory: TrajectorySpec
    controller: ControllerSpec
    solver: SolverSpec = Field(default_factory=SolverSpec)


def _valid_keys(model: type[BaseModel], loc: tuple[Any, ...]) -> list[str]:
    """Field names of the model reached by following ``loc`` (for error messages)."""
    current: Any = model
    for part in loc[:-1]:
        if isinstance(part, int):
            continue
        if not (isinstance(current, type) and issubclass(current, BaseModel)):
            return []
        field = current.model_fields.get(str(part))
        if field is None:
            return []
        current = _model_in(field.annotation)
        if current is None:
            return []
    if isinstance(current, type) and issubclass(current, BaseModel):
        return list(current.model_fields)
    return []


def _model_in(annotation: Any) -> type[BaseModel] | None:
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    for arg in getattr(annotation, "__args__", ()) or ():
        found = _model_in(arg)
        if found is not None:
            return found
    return None


def parse_config(data: Any, path: str = "<config>") -> ExperimentConfig:
    """Validate a loaded YAML document.

    Raises
    ------
    ConfigError
        Naming the file, the first offending key and, for unknown keys, the valid keys.
    """
    if not isinstance(data, dict):
        raise ConfigError("the file must hold a mapping of keys at the top level", path=path)
    try:
        return ExperimentConfig.model_validate(data)
    except ValidationError as err:
        # An unknown key first (a misspelt required key is also "missing"), then bad
        # values, then missing keys.
        rank = {"extra_forbidden": 0, "missing": 2}
        first = min(err.errors(), key=lambda e: rank.get(e["type"], 1))
        loc = tuple(first["loc"])
        # Drop pydantic's union/literal tags from the location.
        clean = tuple(p for p in loc if not (isinstance(p, str) and ("[" in p or p.startswith(
            ("function-", "literal[")))))
        key = ".".join(str(p) for p in clean) or None
        if first["type"] == "extra_forbidden":
            valid = _valid_keys(ExperimentConfig, clean)
            raise ConfigError("unknown key", path=path, key=key, valid=valid) from None
        if first["type"] == "missing":
            raise ConfigError("missing required key", path=path, key=key) from None
        msg = first["msg"]
        if first["type"].startswith("literal_error") and "expected" in first.get("ctx", {}):
            msg = f"invalid value {first.get('input')!r}"
            raise ConfigError(msg, path=path, key=key,
                              valid=[s.strip(" '\"") for s in
                                     str(first["ctx"]["expected"]).replace(" or ", ",").split(",")]
                              ) from None
        msg = msg.removeprefix("Value error, ")
        got = first.get("input")
        if not isinstance(got, (dict, list)):  # a whole section would drown the message
            msg = f"{msg} (got {got!r})"
        raise ConfigError(msg, path=path, key=key) from None


def load_config(path: str | Path) -> ExperimentConfig:
    """Read and validate an experiment file.

    Raises
    ------
    ConfigError
        Missing file, unreadable YAML, or an invalid document (see :func:`parse_config`).
    """
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ConfigError("file not found", path=str(p)) from None
    except OSError as err:
        raise ConfigError(f"cannot read file: {err.strerror}", path=str(p)) from None
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        raise ConfigError(f"not valid YAML{where}: {getattr(err, 'problem', err)}",
                          path=str(p)) from None
    return parse_config(data, str(p))
