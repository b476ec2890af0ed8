"""The ``physics:`` section of an experiment file: servos, thresholds, default object.

::

    physics:
      servo: position          # position (PD on the integrated command) or velocity
      kp: 20000                # N m/rad, position gain (SI whatever the file's units)
      kv: 300                  # N m s/rad, velocity gain
      armature: 0.2            # kg m^2, rotor inertia added to every arm joint
      delay: false             # closed loop: the controller sees the previous sample
      object_mass: 3           # kg, when the object states no mass
      link_density: 1000       # kg/m^3, links whose model has no inertia
      deviation_max: 10        # length unit: the object off D(t) -> dropped
      slip_max: 5              # length unit: a grasp off its commanded place -> slipped
      squeeze_max: 20          # N: internal force above the rigid replay's -> squeezed
      torque_ratio_max: 1.0    # share of the joint torque limit -> torque
      tau_max: {leader: [...], follower: [...]}   # N m; default: the URDF's effort

Every key is optional; the defaults are those above (docs/physics.md says why). The
section is validated with the rest of the file: an unknown key or a bad value is a
:class:`~dualarm_qp.errors.ConfigError` naming the file and ``physics.<key>``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Annotated, Any, Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import Field, model_validator

from ..experiments.config_types import Flag, Model, Num, keyed, scalar_to_list

FloatArray = NDArray[np.float64]

#: Servo kinds: ``position`` (PD about the integrated command, velocity feed-forward)
#: or ``velocity`` (damping about the commanded rate only).
SERVOS = ("position", "velocity")

#: MuJoCo's time step [s]: the controller's ``dt`` is cut into substeps of at most this.
SUBSTEP = 1e-3

NumList = Annotated[list[Num], Field(min_length=1)]


class TorqueLimitSpec(Model):
    """Joint torque limits [N m] per arm: one number for every joint, or one per joint."""

    leader: NumList | None = None
    follower: NumList | None = None

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
                raise keyed(role, "torque limits must be > 0 N m")
        return self


class PhysicsSpec(Model):
    """The ``physics:`` section, as written (lengths in the file's length unit)."""

    servo: Literal["position", "velocity"] = "position"
    kp: Num = 20000.0
    kv: Num = 300.0
    armature: Num = 0.2
    delay: Flag = False
    object_mass: Num = 3.0
    link_density: Num = 1000.0
    deviation_max: Num | None = None
    slip_max: Num | None = None
    squeeze_max: Num = 20.0
    torque_ratio_max: Num = 1.0
    tau_max: TorqueLimitSpec = Field(default_factory=TorqueLimitSpec)

    @model_validator(mode="after")
    def _ranges(self) -> PhysicsSpec:
        for key in ("kv", "object_mass", "link_density", "squeeze_max", "torque_ratio_max"):
            if not getattr(self, key) > 0:
                raise keyed(key, f"must be > 0 (got {getattr(self, key):g})")
        for key in ("kp", "armature"):
            if getattr(self, key) < 0:
                raise keyed(key, f"must be >= 0 (got {getattr(self, key):g})")
        if self.servo == "position" and not self.kp > 0:
            raise keyed("kp", "a position servo needs kp > 0 (or servo: velocity)")
        for key in ("deviation_max", "slip_max"):
            value = getattr(self, key)
            if value is not None and not value > 0:
                raise keyed(key, f"must be > 0 (got {value:g})")
        return self


@dataclass(frozen=True)
class PhysicsSettings:
    """The physics check's settings in SI units (built from :class:`PhysicsSpec`).

    Attributes
    ----------
    servo : {"position", "velocity"}
        Joint servo kind (:data:`SERVOS`).
    kp : float
        Position gain [N m/rad] (position servo only).
    kv : float
        Velocity gain [N m s/rad].
    armature : float
        Rotor inertia added to every arm joint [kg m^2].
    delay : bool
        Closed loop: the controller is handed the measurement of the previous sample.
    object_mass : float
        Mass of an object whose file states none [kg].
    link_density : float
        Density of the capsules that give a link without inertia its mass [kg/m^3].
    deviation_max : float
        Largest deviation of the object from ``D(t)`` before the verdict is
        ``dropped`` [m] (default 10 mm).
    slip_max : float
        Largest slip of a grasp before the verdict is ``slipped`` [m] (default 5 mm).
    squeeze_max : float
        Largest internal force above the rigid replay's before the verdict is
        ``squeezed`` [N].
    torque_ratio_max : float
        Largest share of a joint torque limit before the verdict is ``torque``.
    tau_max : dict of str to ndarray or None
        Torque limits [N m] per arm (``"leader"``, ``"follower"``) given in the file;
        None: the arm model's own (a URDF's ``effort``), if any.
    """

    servo: str = "position"
    kp: float = 20000.0
    kv: float = 300.0
    armature: float = 0.2
    delay: bool = False
    object_mass: float = 3.0
    link_density: float = 1000.0
    deviation_max: float = 0.01
    slip_max: float = 0.005
    squeeze_max: float = 20.0
    torque_ratio_max: float = 1.0
    tau_max: dict[str, FloatArray | None] | None = None

    def __post_init__(self) -> None:
        if self.servo not in SERVOS:
            raise ValueError(f"servo must be one of {SERVOS}, got {self.servo!r}")
        for key in ("kv", "object_mass", "link_density", "deviation_max", "slip_max",
                    "squeeze_max", "torque_ratio_max"):
            value = float(getattr(self, key))
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{key} must be a finite number > 0, got {value}")

    @classmethod
    def from_spec(cls, spec: PhysicsSpec, length_scale: float) -> PhysicsSettings:
        """Convert the file's section (``length_scale`` [m per file unit])."""
        def length(value: float | None, default: float) -> float:
            return default if value is None else value * length_scale

        tau = {role: (None if getattr(spec.tau_max, role) is None
                      else np.asarray(getattr(spec.tau_max, role), dtype=float))
               for role in ("leader", "follower")}
        return cls(servo=spec.servo, kp=spec.kp, kv=spec.kv, armature=spec.armature,
                   delay=spec.delay, object_mass=spec.object_mass,
                   link_density=spec.link_density,
                   deviation_max=length(spec.deviation_max, 0.01),
                   slip_max=length(spec.slip_max, 0.005), squeeze_max=spec.squeeze_max,
                   torque_ratio_max=spec.torque_ratio_max, tau_max=tau)

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready, SI."""
        return {"servo": self.servo, "kp_N_m_rad": self.kp, "kv_N_m_s_rad": self.kv,
                "armature_kg_m2": self.armature, "delay_samples": int(self.delay),
                "substep_s": SUBSTEP, "deviation_max_m": self.deviation_max,
                "slip_max_m": self.slip_max, "squeeze_max_N": self.squeeze_max,
                "torque_ratio_max": self.torque_ratio_max,
                "link_density_kg_m3": self.link_density}


__all__ = ["SERVOS", "SUBSTEP", "PhysicsSettings", "PhysicsSpec", "TorqueLimitSpec"]
