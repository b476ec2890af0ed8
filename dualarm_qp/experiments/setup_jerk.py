"""Jerk limits from the file: each arm's ``qddd_max`` and ``controller.jerk_limits``.

:func:`with_jerk_limits` gives the arms their jerk limits (``<role>.qddd_max``, in the
file's angle unit per time unit cubed; default none) and the step options
``jerk_limits`` and ``grasp_jerk_max`` (length unit per time unit cubed). With
``controller.jerk_limits`` on, every joint of both arms must state one (a robot
description states none), and the acceleration limits must be on too: the jerk limit
bounds how fast an acceleration may change, which is only meaningful where the
acceleration itself is bounded.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..errors import ConfigError
from ..kinematics.arm import SerialArm
from ..step.options import StepOptions
from ..task.scene import DualArmTask
from .config import ExperimentConfig


def _qddd(cfg: ExperimentConfig, role: str, arm: SerialArm, scale: float, path: str
          ) -> np.ndarray | None:
    """Return the arm's ``qddd_max`` in SI [rad/s^3] as the file gives it (checked), or None."""
    values = getattr(cfg, role).qddd_max
    key = f"{role}.qddd_max"
    if values is None:
        return None
    if len(values) != arm.n:
        raise ConfigError(f"needs {arm.n} values (one per joint), got {len(values)}",
                          path=path, key=key)
    arr = np.asarray(values, dtype=float) * scale
    bad = np.flatnonzero(~(arr > 0))
    if bad.size:
        raise ConfigError(f"joint {int(bad[0]) + 1}: a jerk limit must be > 0 (.inf: none), "
                          f"got {values[int(bad[0])]:g}", path=path, key=key)
    return arr


def with_jerk_limits(cfg: ExperimentConfig, task: DualArmTask, options: StepOptions,
                     angle: float, length: float, time: float, path: str
                     ) -> tuple[DualArmTask, StepOptions]:
    """Return the task and the options with the file's jerk limits (see the module).

    ``angle``, ``length`` and ``time`` convert the file's units to SI.

    Raises
    ------
    ConfigError
        A ``qddd_max`` of the wrong length or not positive; ``jerk_limits`` on without
        ``acceleration_limits``, or with a joint that has no jerk limit.
    """
    c = cfg.controller
    arms = {}
    for role in ("leader", "follower"):
        arm = getattr(task, role)
        given = _qddd(cfg, role, arm, angle / time**3, path)
        arms[role] = arm if given is None else arm.with_limits(qddd_max=given)
        missing = np.flatnonzero(~np.isfinite(arms[role].qddd_max))
        if c.jerk_limits and missing.size:
            raise ConfigError(f"controller.jerk_limits is on, but the {role} states no jerk "
                              f"limit for joint {int(missing[0]) + 1}: give {role}.qddd_max, "
                              "one value per joint", path=path, key=f"{role}.qddd_max")
    if c.jerk_limits and not c.acceleration_limits:
        raise ConfigError("jerk limits need acceleration limits: turn "
                          "controller.acceleration_limits on", path=path,
                          key="controller.jerk_limits")
    if arms["leader"] is not task.leader or arms["follower"] is not task.follower:
        task = dataclasses.replace(task, leader=arms["leader"], follower=arms["follower"])
    options = dataclasses.replace(
        options, jerk_limits=c.jerk_limits,
        grasp_jerk_max=math.inf if c.grasp_jerk_max is None
        else c.grasp_jerk_max * length / time**3)
    return task, options


__all__ = ["with_jerk_limits"]
