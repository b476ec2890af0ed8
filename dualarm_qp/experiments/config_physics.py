"""The ``physics:`` section of an experiment file, as written (docs/physics.md).

The settings in SI units are :class:`~dualarm_qp.physics.settings.PhysicsSettings`.
Lengths (``deviation_max``, ``slip_max``) are in the file's length unit and
``rotation_max`` in its angle unit, ``reference_time`` in its time unit; gains, masses,
densities, forces and torques are SI whatever the file's units.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import BeforeValidator, Field, model_validator

from .config_types import Flag, LimitNum, Model, Num, Vec3, keyed, scalar_to_list

LimitList = Annotated[list[LimitNum], Field(min_length=1)]

#: Most samples of delay a file may ask for.
DELAY_MAX = 100


def _samples(value: Any) -> int:
    """Return a delay's samples: ``true`` 1 (the former meaning), ``false`` 0, or a number."""
    if isinstance(value, bool):
        return int(value)
    if isinstance(value, int) and 0 <= value <= DELAY_MAX:
        return value
    raise ValueError(f"must be true (1 sample), false or a whole number of samples from 0 "
                     f"to {DELAY_MAX}, got {value!r}")


#: The closed loop's delay in samples (``true`` is 1, as it was before it took a number).
Samples = Annotated[int, BeforeValidator(_samples)]


class TorqueLimitSpec(Model):
    """Joint torque limits [N m] per arm: one number for every joint, or one per joint.

    ``.inf`` leaves a joint unlimited. The count (1 or the arm's joint count) is checked
    against the arm when the task is built (:func:`dualarm_qp.physics.command.settings_for`).
    """

    leader: LimitList | None = None
    follower: LimitList | None = None

    @model_validator(mode="before")
    @classmethod
    def _lists(cls, data: Any) -> Any:
        if isinstance(data, dict):
            return {k: (scalar_to_list(v) if v is not None else v) for k, v in data.items()}
        return data

    @model_validator(mode="after")
    def _positive(self) -> TorqueLimitSpec:
        for role in ("leader", "follower"):
            values = getattr(self, role)
            if values is not None and not all(v > 0 for v in values):
                raise keyed(role, "torque limits must be > 0 N m (.inf: no limit)")
        return self


class ComplianceSpec(Model):
    """``physics.compliance``: the compliant follower's gains (SI; docs/physics.md)."""

    force_gain: Num = 2e-4
    moment_gain: Num = 2e-3
    filter_time: Num = 0.02

    @model_validator(mode="after")
    def _signs(self) -> ComplianceSpec:
        for key in ("force_gain", "moment_gain", "filter_time"):
            if getattr(self, key) < 0:
                raise keyed(key, f"must be >= 0 (got {getattr(self, key):g})")
        return self


def _switch(value: Any) -> Any:
    """Return ``compliance: true`` as the default gains, ``false`` as none."""
    if value is True:
        return {}
    if value is False:
        return None
    return value


#: ``physics.compliance``: ``true`` (the default gains), ``false`` or the gains.
Compliance = Annotated[ComplianceSpec | None, BeforeValidator(_switch)]


class BaseErrorSpec(Model):
    """``physics.base_error``: the simulated follower's base off the model's.

    In the base's own frame: ``position`` in the file's length unit, ``rpy`` in its
    angle unit.
    """

    position: Vec3 = Field(default_factory=lambda: [0.0, 0.0, 0.0])
    rpy: Vec3 = Field(default_factory=lambda: [0.0, 0.0, 0.0])


class PhysicsSpec(Model):
    """The ``physics:`` section, as written (lengths in the file's length unit)."""

    servo: Literal["position", "velocity"] = "position"
    reference: Literal["measured", "integrated"] = "measured"
    reference_time: Num | None = None
    servo_frequency: Num = 40.0
    damping_ratio: Num = 1.0
    kp: Num | None = None
    kv: Num | None = None
    armature: Num = 0.05
    delay: Samples = 0
    predict: Flag = True
    contacts: Literal["obstacles", "all", "none"] = "obstacles"
    geometry: Literal["meshes", "capsules"] = "meshes"
    object_mass: Num = 3.0
    link_density: Num = 1000.0
    deviation_max: Num | None = None
    rotation_max: Num | None = None
    slip_max: Num | None = None
    squeeze_max: Num = 20.0
    torque_ratio_max: Num = 1.0
    tau_max: TorqueLimitSpec = Field(default_factory=TorqueLimitSpec)
    compliance: Compliance = None
    base_error: BaseErrorSpec | None = None

    @model_validator(mode="after")
    def _ranges(self) -> PhysicsSpec:
        for key in ("servo_frequency", "damping_ratio", "object_mass", "link_density",
                    "squeeze_max", "torque_ratio_max"):
            if not getattr(self, key) > 0:
                raise keyed(key, f"must be > 0 (got {getattr(self, key):g})")
        if self.kv is not None and not self.kv > 0:
            raise keyed("kv", f"must be > 0 (got {self.kv:g}; leave it out for each "
                        "joint's from its inertia)")
        if self.armature < 0:
            raise keyed("armature", f"must be >= 0 (got {self.armature:g})")
        if self.kp is not None and self.kp < 0:
            raise keyed("kp", f"must be >= 0 (got {self.kp:g})")
        if self.servo == "position" and self.kp is not None and not self.kp > 0:
            raise keyed("kp", "a position servo needs kp > 0 (or leave it out for each "
                        "joint's from its inertia, or servo: velocity)")
        for key in ("reference_time", "deviation_max", "rotation_max", "slip_max"):
            value = getattr(self, key)
            if value is not None and not value > 0:
                raise keyed(key, f"must be > 0 (got {value:g})")
        return self



__all__ = ["BaseErrorSpec", "ComplianceSpec", "PhysicsSpec", "TorqueLimitSpec"]
