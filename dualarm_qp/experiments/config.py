"""Experiment configuration files (YAML), validated and converted to SI on load.

Lengths in a file may be given in mm or m and angles in degrees or radians, as the
file's ``units`` block says; everything is converted to SI (m, rad, s) here, at the
boundary, and the library never sees file units. Unknown or misspelled keys are
errors that name the file, the key and the valid keys. The file is read by
:mod:`.yaml_file` (encoding, YAML 1.2 scalars, duplicate keys, nesting) before this
module checks it against the schema.
"""

from __future__ import annotations

import math
import re
import unicodedata
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import (
    BaseModel,
    Field,
    ValidationError,
    field_validator,
    model_validator,
)

from ..errors import ConfigError
from .config_arms import (
    ARM_MODEL_KEYS,
    ArmSpec,
    DHSpec,
    ExampleRobotSpec,
    IKBranch,
    InitialSpec,
    UrdfSpec,
)
from .config_cell import CellSpec
from .config_controller import MAX_SAMPLES, ControllerSpec, SolverSpec, WeightsSpec
from .config_physics import PhysicsSpec
from .config_scene import CollisionSpec, SceneSpec, ShapeSpec
from .config_types import (
    MAX_MAGNITUDE,
    Model,
    Num,
    PoseSpec,
    Units,
    Vec3,
    keyed,
)
from .yaml_file import MAX_DEPTH, read_yaml_document

FloatArray = NDArray[np.float64]

LENGTH_SCALE = {"m": 1.0, "mm": 1e-3}
ANGLE_SCALE = {"rad": 1.0, "deg": math.pi / 180.0}
TIME_SCALE = {"s": 1.0, "ms": 1e-3}

#: Shortest sampling interval [s] after unit conversion (a 1 MHz loop): below it the
#: path time no longer advances reliably in floating point.
MIN_DT_S = 1e-6




class SurfaceSpec(Model):
    """The object surface and the follower's sliding path on it.

    ``plane_bar`` (the paper's bar): the grasp slides along object z on the plane x = 0,
    inside the box ``r_min``..``r_max`` (Eq. 3). ``cylinder`` (radius, azimuth) and
    ``curved_bar`` (radius of the arc, ``side``) take the grasp range ``grasp_range``
    (arc length along the path).
    """

    type: Literal["plane_bar", "cylinder", "curved_bar"] = "plane_bar"
    r_min: Vec3 | None = None
    r_max: Vec3 | None = None
    radius: Num | None = None
    azimuth: Num | None = None
    side: Literal["outer", "inner"] | None = None
    grasp_range: Annotated[list[Num], Field(min_length=2, max_length=2)] | None = None

    @model_validator(mode="after")
    def _fields(self) -> SurfaceSpec:
        if self.type == "plane_bar":
            extra = [k for k in ("radius", "azimuth", "side", "grasp_range")
                     if getattr(self, k) is not None]
            if extra:
                raise keyed(extra[0], f"a plane_bar takes r_min and r_max, not "
                             f"{', '.join(extra)}")
            if self.r_min is not None and self.r_max is not None and any(
                    lo > hi for lo, hi in zip(self.r_min, self.r_max, strict=True)):
                raise keyed("r_min", "must not exceed r_max in any coordinate")
        else:
            if self.radius is None or not self.radius > 0:
                raise keyed("radius", f"a {self.type} needs a positive 'radius'")
            if self.grasp_range is None:
                raise keyed("grasp_range", f"a {self.type} needs 'grasp_range: [min, max]'")
            if self.grasp_range[0] > self.grasp_range[1]:
                raise keyed("grasp_range", "must be [min, max] with min <= max")
            for k in ("r_min", "r_max"):
                if getattr(self, k) is not None:
                    raise keyed(k, f"a {self.type} takes grasp_range, not r_min / r_max")
            if self.type == "cylinder" and self.side is not None:
                raise keyed("side", "'side' is for a curved_bar")
            if self.type == "curved_bar" and self.azimuth is not None:
                raise keyed("azimuth", "'azimuth' is for a cylinder")
        return self


class ObjectSpec(Model):
    """The carried object.

    ``surface`` and ``grasp_initial`` are the follower's sliding path and its start.
    ``leader_surface`` and ``leader_grasp_initial`` (both or neither) let the leader's
    grasp slide too, on its own path in object coordinates; the object is then placed
    by that path (``H1`` must be left out).

    ``contact`` says how the follower holds the object: ``grasp`` (the default, Case 1)
    or ``support`` (Case 2: it only pushes along the surface normal, on the support line
    that gravity sets, docs/support.md). ``mass`` [kg] (> 0), ``mass_centre`` (object
    coordinates, length unit; default the object origin) and ``gravity`` (world frame,
    length unit / time unit^2, non-zero; default ``[0, 0, -9.81]`` m/s^2) describe the
    load: with a grasp they are optional (given, the run records the wrench each hand
    applies, docs/derivation.md "The load each hand carries"; ``mass_centre`` and
    ``gravity`` need ``mass``); a support needs ``mass``, a ``plane_bar`` surface and a
    rigid leader grasp.
    """

    H1: PoseSpec | None = None
    surface: SurfaceSpec = Field(default_factory=SurfaceSpec)
    grasp_initial: Num
    leader_surface: SurfaceSpec | None = None
    leader_grasp_initial: Num | None = None
    contact: Literal["grasp", "support"] = "grasp"
    mass: Num | None = None
    mass_centre: Vec3 | None = None
    gravity: Vec3 | None = None
    shape: ShapeSpec | None = None

    @model_validator(mode="after")
    def _contact(self) -> ObjectSpec:
        if self.mass is not None and not self.mass > 0:
            raise keyed("mass", f"must be > 0 kg (got {self.mass:g})")
        if self.gravity is not None and not any(self.gravity):
            raise keyed("gravity", "must be a non-zero vector")
        if self.contact == "grasp":
            given = [k for k in ("mass_centre", "gravity") if getattr(self, k) is not None]
            if given and self.mass is None:
                raise keyed(given[0], "describes the load, which needs 'mass' [kg] too "
                             "(without a mass no load is computed)")
            return self
        if self.mass is None:
            raise keyed("mass", "missing required key: a supporting follower ('contact: "
                         "support') needs the object's mass [kg]")
        if self.surface.type != "plane_bar":
            raise keyed("surface.type", f"a support ('contact: support') needs a plane_bar "
                         f"surface, got {self.surface.type}")
        if self.leader_surface is not None:
            raise keyed("leader_surface", "a support ('contact: support') needs a rigid "
                         "leader grasp: leave 'leader_surface' out")
        return self

    @model_validator(mode="after")
    def _leader_grasp(self) -> ObjectSpec:
        if (self.leader_surface is None) != (self.leader_grasp_initial is None):
            missing = "leader_grasp_initial" if self.leader_grasp_initial is None \
                else "leader_surface"
            raise keyed(missing, "a sliding leader grasp needs both 'leader_surface' and "
                         "'leader_grasp_initial'")
        if self.leader_surface is not None and self.H1 is not None:
            raise keyed("H1", "with a sliding leader grasp the object is placed by "
                         "'leader_surface': leave 'H1' out")
        return self


class Waypoint(Model):
    """One waypoint of the object path."""

    t: Num
    pose: PoseSpec


class TrajectorySpec(Model):
    """The desired object path D(t) in the world."""

    type: Literal["linear", "waypoints"] = "linear"
    start: PoseSpec | None = None
    velocity: Vec3 | None = None
    waypoints: Annotated[list[Waypoint], Field(max_length=100_000)] | None = None

    @model_validator(mode="after")
    def _fields(self) -> TrajectorySpec:
        if self.type == "linear":
            for k in ("start", "velocity"):
                if getattr(self, k) is None:
                    raise keyed(k, "a linear trajectory needs 'start' and 'velocity'")
            if self.waypoints is not None:
                raise keyed("waypoints", "a linear trajectory takes start and velocity, "
                             "not waypoints")
        if self.type == "waypoints":
            if not self.waypoints or len(self.waypoints) < 2:
                raise keyed("waypoints", "a waypoints trajectory needs at least two "
                             "'waypoints'")
            times = [w.t for w in self.waypoints]
            bad = next((i for i in range(1, len(times)) if times[i] <= times[i - 1]), None)
            if bad is not None:
                raise keyed(f"waypoints.{bad}.t", "waypoint times must be strictly "
                             f"increasing (got {times[bad - 1]:g} then {times[bad]:g})")
            for k in ("start", "velocity"):
                if getattr(self, k) is not None:
                    raise keyed(k, "a waypoints trajectory takes waypoints, not start / "
                                 "velocity")
        return self


class ExperimentConfig(Model):
    """A whole experiment file (the values as written, in the file's units)."""

    name: Annotated[str, Field(min_length=1, max_length=200)] = "experiment"
    description: str = ""
    units: Units = Field(default_factory=Units)
    leader: ArmSpec
    follower: ArmSpec
    object: ObjectSpec
    trajectory: TrajectorySpec
    controller: ControllerSpec
    solver: SolverSpec = Field(default_factory=SolverSpec)
    scene: SceneSpec = Field(default_factory=SceneSpec)
    collision: CollisionSpec = Field(default_factory=CollisionSpec)
    physics: PhysicsSpec = Field(default_factory=PhysicsSpec)  # docs/physics.md
    cell: CellSpec = Field(default_factory=CellSpec)  # docs/robots.md

    @field_validator("name")
    @classmethod
    def _printable(cls, v: str) -> str:
        bad = next((c for c in v if unicodedata.category(c)[0] == "C"), None)
        if bad is not None:
            raise ValueError(f"must be printable text (it holds the control character "
                             f"U+{ord(bad):04X})")
        if not any(c.isalnum() for c in v):
            raise ValueError("must hold at least one letter or digit")
        return v


def safe_name(name: str) -> str:
    """Return ``name`` as one safe file-name component (the default run folder's).

    Every character other than a letter, a digit, ``-``, ``_`` or ``.`` becomes ``_``
    (path separators, NUL and other control characters, spaces); leading dots are
    dropped (no ``..``, no hidden folder) and the result is cut to 100 characters.
    Always non-empty: ``"experiment"`` when nothing usable is left.

    Examples
    --------
    >>> safe_name("../../escape")
    '_.._escape'
    >>> safe_name("beam s7=100")
    'beam_s7_100'
    """
    text = unicodedata.normalize("NFKC", str(name))
    out = re.sub(r"[^\w.-]", "_", text, flags=re.ASCII).lstrip(".")
    out = out[:100].rstrip(".")
    return out or "experiment"


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


def _location(err: Any) -> tuple[Any, ...]:
    """Return the error's location without pydantic's union and validator tags."""
    loc = list(err["loc"])
    ctx = err.get("ctx") or {}
    if err["type"] == "keyed" and ctx.get("key"):
        loc.extend(int(p) if p.isdigit() else p for p in str(ctx["key"]).split("."))
    return tuple(p for p in loc if not (isinstance(p, str) and (
        "[" in p or p.startswith(("function-", "literal[")))))


def parse_config(data: Any, path: str = "<config>") -> ExperimentConfig:
    """Validate a loaded YAML document.

    Raises
    ------
    ConfigError
        Naming the file, the first offending key and, for unknown keys and fixed
        choices, the valid ones.
    """
    if not isinstance(data, dict):
        kind = "empty" if data is None else f"a {_yaml_kind(data)}"
        raise ConfigError(f"the top level of the file must be a mapping of keys "
                          f"(name, leader, follower, ...), but it is {kind}", path=path)
    try:
        return ExperimentConfig.model_validate(data)
    except ValidationError as err:
        raise _config_error(err, path) from None
    except RecursionError:
        raise ConfigError(f"the document is nested too deeply (more than {MAX_DEPTH} "
                          "levels)", path=path) from None


def _yaml_kind(value: Any) -> str:
    if isinstance(value, list):
        return "list"
    if isinstance(value, str):
        return "text"
    if isinstance(value, bool):
        return "boolean"
    if isinstance(value, (int, float)):
        return "number"
    return type(value).__name__


def _config_error(err: ValidationError, path: str) -> ConfigError:
    """Return the ConfigError for the most telling of pydantic's errors."""
    # An unknown key first (a misspelt required key is also "missing"), then bad
    # values, then missing keys; a union's "should be a valid list" loses to the
    # other branch's complaint.
    rank = {"extra_forbidden": 0, "missing": 3, "list_type": 2, "dict_type": 2,
            "model_type": 2}
    first = min(err.errors(), key=lambda e: rank.get(e["type"], 1))
    clean = _location(first)
    key = ".".join(str(p) for p in clean) or None
    if first["type"] == "extra_forbidden":
        valid = _valid_keys(ExperimentConfig, clean)
        return ConfigError("unknown key", path=path, key=key, valid=valid)
    if first["type"] == "missing":
        return ConfigError("missing required key", path=path, key=key)
    ctx = first.get("ctx") or {}
    if first["type"].startswith("literal_error") and "expected" in ctx:
        return ConfigError(
            f"invalid value {first.get('input')!r}", path=path, key=key,
            valid=[s.strip(" '\"") for s in
                   str(ctx["expected"]).replace(" or ", ",").split(",")])
    msg = str(ctx.get("message", first["msg"])).removeprefix("Value error, ")
    if first["type"] in ("less_than_equal", "greater_than_equal"):
        msg = f"must be between {-MAX_MAGNITUDE:g} and {MAX_MAGNITUDE:g}"
    if first["type"] in ("model_type", "dict_type"):
        valid = _valid_keys(ExperimentConfig, (*clean, ""))
        return ConfigError(f"must be a mapping of keys, got {_yaml_kind(first.get('input'))}",
                           path=path, key=key, valid=valid)
    got = first.get("input")
    if first["type"] != "keyed" and not isinstance(got, (dict, list)):
        text = repr(got)  # a whole section would drown the message
        msg = f"{msg} (got {text if len(text) <= 60 else text[:57] + '...'})"
    return ConfigError(msg, path=path, key=key)


def _schema_key(keys: tuple[str, ...]) -> str:
    """Return the part of a key path that the schema knows (plus one free mapping key).

    ``solver.options.x.0.0...`` gives ``solver.options.x``, ``description.a.a...`` gives
    ``description``: where a runaway structure starts.
    """
    current: Any = ExperimentConfig
    out: list[str] = []
    for part in keys:
        if isinstance(current, type) and issubclass(current, BaseModel):
            if part.isdigit():  # an item of a list of models
                out.append(part)
                continue
            field = current.model_fields.get(part)
            if field is None:
                out.append(part)
                break
            out.append(part)
            current = _model_in(field.annotation) or (
                dict if "dict" in str(field.annotation) else None)
            continue
        if current is dict:
            out.append(part)
        break
    return ".".join(out)


def load_config(path: str | Path) -> ExperimentConfig:
    """Read and validate an experiment file.

    Raises
    ------
    ConfigError
        Missing file, unreadable YAML, or an invalid document (see :func:`parse_config`).
    """
    return parse_config(read_yaml_document(path, schema_key=_schema_key), str(Path(path)))


__all__ = ["ANGLE_SCALE", "ARM_MODEL_KEYS", "LENGTH_SCALE", "MAX_SAMPLES", "MIN_DT_S",
           "TIME_SCALE", "ArmSpec", "ControllerSpec", "DHSpec", "ExampleRobotSpec",
           "ExperimentConfig", "IKBranch", "InitialSpec", "ObjectSpec", "PoseSpec",
           "SolverSpec", "SurfaceSpec", "TrajectorySpec", "UrdfSpec", "Waypoint",
           "WeightsSpec", "load_config", "parse_config", "safe_name"]
