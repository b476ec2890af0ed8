"""The controller section of an experiment file: the run's limits and the step's options."""

from __future__ import annotations

import math

import numpy as np

from ..control.run_limits import RunLimits
from ..errors import ConfigError
from ..kinematics.arm import SerialArm
from ..step.options import StepOptions
from .config import LENGTH_SCALE, ExperimentConfig
from .setup_arms import tau_max_of
from .setup_values import Scales, at_key


def run_limits_of(cfg: ExperimentConfig, sc: Scales, path: str) -> RunLimits:
    """Return the run's tolerances, singularity threshold and duration cap, in SI."""
    c = cfg.controller

    def tolerance(value: list[float] | None) -> tuple[float, float]:
        return (1e-3, 1e-2) if value is None else (value[0] * sc.length, value[1] * sc.angle)

    with at_key("controller", path):
        return RunLimits(
            closure=tolerance(c.closure_tolerance), tracking=tolerance(c.tracking_tolerance),
            singular_value_min=c.singular_value_min, singularity_action=c.singularity_action,
            duration_cap=None if c.duration_cap is None else c.duration_cap * sc.time)


def step_options_of(cfg: ExperimentConfig, sc: Scales, dt: float, leader: SerialArm,
                    follower: SerialArm, path: str) -> StepOptions:
    """Return the step's settings in SI for a sampling interval ``dt`` [s].

    The weights hold one value or one per joint; the torque limits are the file's
    ``tau_max`` (checked against the arms when ``controller.torque_limits`` is on).
    """
    c = cfg.controller
    tau_max = {role: tau_max_of(getattr(cfg, role), arm, role, c.torque_limits, path)
               for role, arm in (("leader", leader), ("follower", follower))}
    weights = np.asarray(c.weights.joints, dtype=float)
    if weights.size not in (1, follower.n):
        raise ConfigError(f"needs one weight or {follower.n} (one per follower joint), got "
                          f"{weights.size}", path=path, key="controller.weights.joints")
    leader_weights = np.asarray(c.weights.leader_joints, dtype=float)
    if leader_weights.size not in (1, leader.n):
        raise ConfigError(f"needs one weight or {leader.n} (one per leader joint), got "
                          f"{leader_weights.size}", path=path,
                          key="controller.weights.leader_joints")
    with at_key("controller", path):
        return StepOptions(
            dt=dt,
            joint_weights=np.broadcast_to(weights, (follower.n,)).copy(),
            leader_joint_weights=np.broadcast_to(leader_weights, (leader.n,)).copy(),
            grasp_weight=c.weights.grasp / LENGTH_SCALE[c.weights.grasp_unit
                                                        or cfg.units.length]**2,
            velocity_limits=c.velocity_limits,
            grasp_speed_max=math.inf if c.grasp_speed_max is None
            else c.grasp_speed_max * sc.length / sc.time,
            acceleration_limits=c.acceleration_limits,
            torque_limits=c.torque_limits,
            torque_approach=None if c.torque_approach is None else c.torque_approach * sc.time,
            leader_tau_max=tau_max["leader"],
            follower_tau_max=tau_max["follower"],
            grasp_acc_max=math.inf if c.grasp_acc_max is None
            else c.grasp_acc_max * sc.length / sc.time**2,
            correction_gain=None if c.correction_gain is None else c.correction_gain / sc.time,
            leader_gain=None if c.leader_gain is None else c.leader_gain / sc.time,
            recovery_fraction=c.recovery_fraction,
            exact_orientation=c.exact_orientation,
            centre_horizon=None if c.centre_horizon is None else c.centre_horizon * sc.time,
        )


__all__ = ["run_limits_of", "step_options_of"]
