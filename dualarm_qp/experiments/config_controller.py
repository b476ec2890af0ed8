"""The controller's and the solver's part of an experiment file's schema."""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal

from pydantic import BeforeValidator, Field, field_validator, model_validator

from .config_types import Flag, Model, Num, keyed, scalar_to_list

#: Most samples a run may take: ``duration_cap / dt`` (``duration_cap`` defaults to twice
#: ``duration``). Each sample keeps about 60 numbers, so this is about 1 GB at most.
MAX_SAMPLES = 2_000_000


class WeightsSpec(Model):
    """Diagonal of S (Eq. 37).

    ``joints`` weighs follower joint rates in (rad/s)^-2 whatever the file's angle unit,
    ``leader_joints`` the leader's (they matter when it has more than six joints);
    ``grasp`` (the paper's s7) weighs the sliding speed in (grasp_unit / s)^-2, where
    ``grasp_unit`` defaults to the file's length unit: ``grasp: 100`` with
    ``grasp_unit: mm`` is 1e8 in SI, with ``grasp_unit: m`` it is 100.
    """

    joints: Annotated[list[Num], BeforeValidator(scalar_to_list),
                      Field(min_length=1)] = Field(default_factory=lambda: [1.0])
    leader_joints: Annotated[list[Num], BeforeValidator(scalar_to_list),
                             Field(min_length=1)] = Field(default_factory=lambda: [1.0])
    grasp: Num = 1.0
    grasp_unit: Literal["m", "mm"] | None = None

    @field_validator("joints", "leader_joints", "grasp")
    @classmethod
    def _positive(cls, v: Any) -> Any:
        if not all(w > 0 for w in (v if isinstance(v, list) else [v])):
            raise ValueError("weights must be finite and > 0")
        return v


class ControllerSpec(Model):
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
    ``torque_limits`` keeps every joint's quasi-static torque (its arm's weight and its
    hand's share of ``object.mass``) within its arm's ``tau_max`` (N m, whatever the
    units; default a URDF's ``effort``; a DH arm or preset must give it), and
    ``torque_approach`` (time unit, default none) is the time constant with which a
    torque may approach its limit (each sample closes at most ``dt / torque_approach``
    of the margin).
    ``acceleration_limits`` keeps every joint within its arm's ``qdd_max`` and every
    grasp within ``grasp_acc_max`` (length unit / time unit^2); ``initial_rates`` says
    how the run starts: ``rest`` (the default) or ``path`` (already moving as the first
    step of the path asks, its answer without acceleration limits). ``jerk_limits``
    keeps every joint within its arm's ``qddd_max`` and every grasp within
    ``grasp_jerk_max`` (length unit / time unit^3); it needs ``acceleration_limits``.
    """

    dt: Num
    duration: Num
    weights: WeightsSpec = Field(default_factory=WeightsSpec)
    velocity_limits: Flag = True
    grasp_speed_max: Num | None = None
    acceleration_limits: Flag = False
    torque_limits: Flag = False
    torque_approach: Num | None = None
    grasp_acc_max: Num | None = None
    jerk_limits: Flag = False
    grasp_jerk_max: Num | None = None
    initial_rates: Literal["rest", "path"] = "rest"
    correction_gain: Num | None = None
    leader_gain: Num | None = None
    centre_horizon: Num | None = None
    recovery_fraction: Num = 0.0
    policy: Literal["scale", "relax", "stop"] = "scale"
    exact_orientation: Flag = False
    projection: Flag | None = None
    closure_tolerance: Annotated[list[Num], Field(min_length=2, max_length=2)] | None = None
    tracking_tolerance: Annotated[list[Num], Field(min_length=2, max_length=2)] | None = None
    singular_value_min: Num = 1e-3
    singularity_action: Literal["warn", "stop", "ignore"] = "warn"
    duration_cap: Num | None = None

    @field_validator("singular_value_min")
    @classmethod
    def _non_negative_value(cls, v: float) -> float:
        if not (math.isfinite(v) and v >= 0):
            raise ValueError("must be a finite number >= 0")
        return v

    @model_validator(mode="after")
    def _cap(self) -> ControllerSpec:
        if self.duration_cap is not None and self.duration_cap < self.duration:
            raise keyed("duration_cap", f"duration_cap ({self.duration_cap:g}) must be at "
                         f"least the duration ({self.duration:g})")
        if self.duration < self.dt:
            raise keyed("duration", f"the duration ({self.duration:g}) is shorter than "
                         f"one sample (dt = {self.dt:g}); it must be at least dt")
        cap = 2.0 * self.duration if self.duration_cap is None else self.duration_cap
        samples = cap / self.dt
        if samples > MAX_SAMPLES:
            raise keyed("dt", f"dt = {self.dt:g} with a run of up to {cap:g} (duration_cap, "
                         f"default twice duration) asks for {samples:.3g} samples; at most "
                         f"{MAX_SAMPLES:,} are allowed: raise dt or shorten the run")
        return self

    @field_validator("dt", "duration", "centre_horizon", "grasp_speed_max", "duration_cap",
                     "grasp_acc_max", "torque_approach", "grasp_jerk_max")
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


class SolverSpec(Model):
    """Which solver from the registry, with its options.

    ``fallback`` names the solver that takes a step on which a hard-limit solver fails
    although the step is feasible (default ``nullspace``, the exact solver; ``none``
    lets such a step fail the run).
    """

    name: str = "reference"
    options: dict[str, Any] = Field(default_factory=dict)
    fallback: str = "nullspace"

    @field_validator("options")
    @classmethod
    def _scalars(cls, v: dict[str, Any]) -> dict[str, Any]:
        for key, value in v.items():
            if not (value is None or isinstance(value, (bool, int, float, str))):
                raise keyed(key, "a solver option must be a single value (number, "
                             f"true/false or text), got a {type(value).__name__}")
        return v


__all__ = ["MAX_SAMPLES", "ControllerSpec", "SolverSpec", "WeightsSpec"]
