"""The path of an experiment file: the object's ``D(t)``, and the leader's targets along it."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..task.scene import DualArmTask
from ..task.trajectory import LinearTrajectory, Trajectory, WaypointTrajectory
from .config import ExperimentConfig
from .setup_values import Scales, at_key, file_pose, required

FloatArray = NDArray[np.float64]


def trajectory_of(cfg: ExperimentConfig, sc: Scales, duration: float) -> Trajectory:
    """Return the object's path ``D(t)`` in SI (a line over ``duration`` [s], or waypoints)."""
    tr = cfg.trajectory
    if tr.type == "linear":
        T0 = file_pose(required(tr.start, "trajectory.start"), sc)
        v = np.asarray(required(tr.velocity, "trajectory.velocity"), dtype=float) * (
            sc.length / sc.time)
        return LinearTrajectory(T0[:3, 3], v, R0=T0[:3, :3], t0=0.0, tf=duration)
    waypoints = required(tr.waypoints, "trajectory.waypoints")
    times = [w.t * sc.time for w in waypoints]
    poses = [file_pose(w.pose, sc) for w in waypoints]
    return WaypointTrajectory(times, poses)


def path_targets(cfg: ExperimentConfig, task: DualArmTask, sigma_l0: float, path: str
                 ) -> list[tuple[str, FloatArray]]:
    """Return the leader's targets ``D(t) H1^-1`` at the path's ends or waypoints, named."""
    trajectory = task.trajectory
    hand = "object.H1" if task.leader_surface is None else "object.leader_grasp_initial"
    if cfg.trajectory.type == "linear":
        named = [(trajectory.t0, f"D(t0) H1^-1 at the path's start (trajectory.start, {hand})"),
                 (trajectory.tf, "D(t) H1^-1 at the path's end (trajectory.start, "
                                 f"trajectory.velocity, {hand})")]
    else:
        times = (trajectory.times.tolist() if isinstance(trajectory, WaypointTrajectory)
                 else [trajectory.t0, trajectory.tf])
        named = [(float(t), f"D(t) H1^-1 at t = {t:g} s (trajectory.waypoints.{i}.pose, "
                            f"{hand})") for i, t in enumerate(times)]
    with at_key("trajectory", path):
        return [(what, task.leader_target(t, sigma_l0)) for t, what in named]


__all__ = ["path_targets", "trajectory_of"]
