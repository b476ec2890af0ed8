"""The ``cell:`` section of an experiment file, as written (``docs/robots.md``).

How ``dualarm-qp drive`` reaches the two arms: the watchdog and the other guards, and per
arm its joint names and topics (ROS 2) or its address (Franka). ``watchdog`` is in the
file's time unit, ``start_tolerance`` and ``range_margin`` in its angle unit; rates are
in Hz; ``headroom`` is a fraction. Every key is optional: a file without a ``cell:``
section drives the MuJoCo cell with the defaults.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, model_validator

from .config_types import Flag, Model, Num, keyed

#: The default share of every joint speed, acceleration and jerk limit a cell's commands
#: leave to the servos (their tracking error): commands keep ``1 - headroom`` of each.
HEADROOM = 0.1

JointNames = Annotated[list[Annotated[str, Field(min_length=1, max_length=200)]],
                       Field(min_length=1, max_length=64)]
Text = Annotated[str, Field(min_length=1, max_length=300)]


class CellArmSpec(Model):
    """One arm of the cell.

    ``joints``: the robot's joint names in the arm's order (ROS 2: mapped by name in
    every ``JointState``); ``state_topic``: where its joint states come from (default
    ``/joint_states``); ``controller``: its ``forward_command_controller`` (commands on
    ``<controller>/commands``); ``trajectory_controller``: its
    ``joint_trajectory_controller`` (``<controller>/joint_trajectory``); ``address``: a
    Franka's address; ``rate``: the driver's rate [Hz] (the interpolated command stream's).
    """

    joints: JointNames | None = None
    state_topic: Text = "/joint_states"
    controller: Text | None = None
    trajectory_controller: Text | None = None
    address: Text | None = None
    rate: Num = 500.0

    @model_validator(mode="after")
    def _checked(self) -> CellArmSpec:
        if not self.rate > 0:
            raise keyed("rate", f"must be > 0 Hz (got {self.rate:g})")
        if self.joints is not None and len(set(self.joints)) != len(self.joints):
            raise keyed("joints", "a joint name appears twice")
        return self


class CellSpec(Model):
    """The ``cell:`` section (see the module).

    ROS 2: ``interface``, what each arm's ``forward_command_controller`` claims
    (``velocity``: the rates are sent; ``position``: the rates integrated from the
    measured start); ``node``, the node's name; ``use_sim_time``, the node's clock is
    ``/clock`` (a simulator's) rather than the system clock.
    """

    watchdog: Num | None = None
    start_tolerance: Num | None = None
    range_margin: Num = 0.0
    headroom: Num = HEADROOM
    realtime: Flag = False
    interface: Literal["velocity", "position"] = "velocity"
    node: Text = "dualarm_qp"
    use_sim_time: Flag = False
    leader: CellArmSpec = Field(default_factory=CellArmSpec)
    follower: CellArmSpec = Field(default_factory=CellArmSpec)

    @model_validator(mode="after")
    def _checked(self) -> CellSpec:
        for key in ("watchdog", "start_tolerance"):
            value = getattr(self, key)
            if value is not None and not value > 0:
                raise keyed(key, f"must be > 0 (got {value:g})")
        if not self.range_margin >= 0:
            raise keyed("range_margin", f"must be >= 0 (got {self.range_margin:g})")
        if not 0 <= self.headroom < 1:
            raise keyed("headroom", f"must be in [0, 1) (got {self.headroom:g})")
        return self


__all__ = ["HEADROOM", "CellArmSpec", "CellSpec"]
