"""The arms' part of an experiment file's schema: each arm's model, base, limits and start."""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import BeforeValidator, Field, field_validator, model_validator

from .config_types import Indicator, LimitNum, Model, Num, PoseSpec


class DHSpec(Model):
    """A DH table: rows ``[a, alpha, d]`` or ``[a, alpha, d, offset]``."""

    convention: Literal["standard", "modified"] = "standard"
    rows: list[list[Num]] = Field(min_length=1, max_length=32)

    @field_validator("rows")
    @classmethod
    def _rows(cls, rows: list[list[float]]) -> list[list[float]]:
        widths = {len(r) for r in rows}
        if len(widths) != 1 or widths.pop() not in (3, 4):
            raise ValueError("every DH row must have 3 or 4 numbers [a, alpha, d(, offset)]")
        return rows


class IKBranch(Model):
    """Closed-form IK branch indicators (+1 / -1) for the PUMA 560, all three required."""

    arm: Indicator
    elbow: Indicator
    wrist: Indicator


class InitialSpec(Model):
    """Initial joints: given, or solved at the arm's target pose at t0.

    ``joints`` are the initial joints; ``ik_branch`` (PUMA 560 preset) solves the
    target pose in closed form on that branch; ``near`` solves it by damped least
    squares starting from these joints (any arm). The leader's target pose is
    ``D(t0) H1^-1``, the follower's ``D(t0) H2(grasp_initial)``; the follower's needs
    an explicit ``base``.
    """

    joints: list[Num] | None = None
    ik_branch: IKBranch | None = None
    near: list[Num] | None = None

    @model_validator(mode="after")
    def _one(self) -> InitialSpec:
        given = [k for k in ("joints", "ik_branch", "near") if getattr(self, k) is not None]
        if len(given) != 1:
            raise ValueError("give exactly one of 'joints', 'ik_branch' or 'near'"
                             + (f" (got {', '.join(given)})" if given else ""))
        return self


def _name(value: Any) -> Any:
    if not isinstance(value, str) or not value.strip():
        raise ValueError("must be a non-empty text")
    return value


#: A non-empty name (a file, a robot, a frame of a URDF).
Name = Annotated[str, BeforeValidator(_name)]


class UrdfSpec(Model):
    """One chain of a URDF, from link ``root`` (the base frame) to link ``tip``.

    ``file`` is relative to the experiment file's folder, or absolute.
    """

    file: Name
    root: Name
    tip: Name


class ExampleRobotSpec(Model):
    """One chain of a robot of example-robot-data (``name``: ur5, panda, baxter, ...)."""

    name: Name
    root: Name
    tip: Name


#: The keys of an arm that each give its kinematic model; exactly one is given.
ARM_MODEL_KEYS = ("preset", "dh", "urdf", "example_robot")


class ArmSpec(Model):
    """One arm: its model (a preset, a DH table or a URDF chain), base, limits, start."""

    preset: Literal["puma560"] | None = None
    dh: DHSpec | None = None
    urdf: UrdfSpec | None = None
    example_robot: ExampleRobotSpec | None = None
    base: PoseSpec | Literal["auto"] = Field(default_factory=PoseSpec)
    tool: PoseSpec | None = None
    q_min: list[LimitNum] | None = None
    q_max: list[LimitNum] | None = None
    qd_max: list[LimitNum] | None = None
    qdd_max: list[LimitNum] | None = None
    qddd_max: list[LimitNum] | None = None
    tau_max: list[LimitNum] | None = None
    link_radius: Annotated[list[Num], Field(min_length=1, max_length=64)] | None = None
    initial: InitialSpec

    @model_validator(mode="after")
    def _one_model(self) -> ArmSpec:
        given = [k for k in ARM_MODEL_KEYS if getattr(self, k) is not None]
        if len(given) != 1:
            raise ValueError("give exactly one of 'preset', 'dh', 'urdf' or 'example_robot'"
                             + (f" (got {', '.join(given)})" if given else ""))
        return self

    @property
    def model_key(self) -> str:
        """The key that gives this arm's model (one of :data:`ARM_MODEL_KEYS`)."""
        return next(k for k in ARM_MODEL_KEYS if getattr(self, k) is not None)


__all__ = ["ARM_MODEL_KEYS", "ArmSpec", "DHSpec", "ExampleRobotSpec", "IKBranch", "InitialSpec",
           "UrdfSpec"]
