"""The collision scene of an experiment file, in SI units.

It is read from the file's ``scene:``, ``collision:``, ``object.shape`` and the arms'
``link_radius``.

A task gets a scene when the file gives any geometry (an obstacle, the object's shape)
or enables collision avoidance. With ``collision.enabled: false`` the scene is only
measured (the clearance columns of the trace); with ``true`` the step keeps it
(:mod:`dualarm_qp.step.limits.collision`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..collision.scene import CollisionScene, ObstacleOverlapError
from ..collision.settings import CollisionSettings
from ..errors import ConfigError, DualArmError
from ..geometry.shapes import Box, Capsule
from ..kinematics.arm import SerialArm
from ..poses import pose
from .config import ArmSpec, ExperimentConfig
from .config_scene import ShapeSpec
from .config_types import PoseSpec

FloatArray = NDArray[np.float64]


def shape_of(spec: ShapeSpec, length: float, angle: float) -> Capsule | Box:
    """Return the shape of ``spec`` in SI.

    A capsule lies along its pose's z axis, centred on the pose; a sphere sits at the
    pose's position; a box is centred on the pose.

    Parameters
    ----------
    spec : ShapeSpec
        The file's shape (validated by the schema).
    length, angle : float
        The file's length and angle units in metres and radians.
    """
    T = _pose(spec.pose, length, angle)
    if spec.box is not None:
        return Box(np.asarray(spec.box.size, dtype=float) * length, T)
    if spec.sphere is not None:
        c = T[:3, 3]
        return Capsule(c, c, spec.sphere.radius * length)
    cap = spec.capsule
    assert cap is not None  # the schema asks for exactly one shape
    half = 0.5 * cap.length * length * T[:3, 2]
    return Capsule(T[:3, 3] - half, T[:3, 3] + half, cap.radius * length)


def scene_of(cfg: ExperimentConfig, length: float, angle: float, time: float,
             leader: SerialArm, follower: SerialArm, start: tuple[FloatArray, FloatArray,
                                                                  FloatArray],
             dt: float, path: str) -> CollisionScene | None:
    """Return the file's collision scene, or None when it gives no geometry.

    Parameters
    ----------
    cfg : ExperimentConfig
        The validated file.
    length, angle, time : float
        Its units in metres, radians and seconds.
    leader, follower : SerialArm
        The arms, placed.
    start : (q_l, q_f, T_object)
        Joints [rad] and object pose [m] at the start.
    dt : float
        Sampling interval [s] (``xi dt <= d_i - d_s`` is checked).
    path : str
        File name, for errors.

    Raises
    ------
    ConfigError
        Distances that cannot work, an arm without collision shapes, an excluded name
        that is no body, naming the key.
    """
    c = cfg.collision
    wanted = c.enabled or cfg.scene.obstacles or cfg.object.shape is not None
    if not wanted:
        return None
    try:
        settings = CollisionSettings(
            enabled=bool(c.enabled), influence_distance=c.influence_distance * length,
            safety_distance=c.safety_distance * length,
            approach_speed_max=c.approach_speed_max * length / time,
            grasp_clearance=c.grasp_clearance * length)
        settings.check_dt(dt)
    except DualArmError as err:
        raise ConfigError(str(err), path=path, key="collision.approach_speed_max") from None
    object_shape = None
    if cfg.object.shape is not None:
        object_shape = shape_of(cfg.object.shape, length, angle)
    obstacles = []
    for i, spec in enumerate(cfg.scene.obstacles):
        try:
            obstacles.append((spec.name, shape_of(spec, length, angle)))
        except DualArmError as err:
            raise ConfigError(str(err), path=path, key=f"scene.obstacles.{i}") from None
    radii = {}
    for role, arm, arm_spec in (("leader", leader, cfg.leader),
                                ("follower", follower, cfg.follower)):
        radii[role] = _radii(arm_spec, arm, role, length, path)
    try:
        return CollisionScene.build(
            leader, follower, settings=settings, object_shape=object_shape,
            obstacles=obstacles, leader_radii=radii["leader"],
            follower_radii=radii["follower"], exclude=[tuple(p) for p in c.exclude],
            start=start)
    except ConfigError:
        raise
    except ObstacleOverlapError as err:
        index = [o.name for o in cfg.scene.obstacles].index(err.obstacle)
        raise ConfigError(str(err), path=path, key=f"scene.obstacles.{index}.pose") from None
    except DualArmError as err:
        key = "collision.exclude" if "no body of the scene" in str(err) else "collision"
        raise ConfigError(str(err), path=path, key=key) from None


def _radii(spec: ArmSpec, arm: SerialArm, role: str, length: float, path: str) -> Any:
    """Return the arm's capsule radii [m] (DH arms), checked against its links."""
    if spec.link_radius is None:
        if arm.dh is not None and arm.source != "preset:puma560":
            raise ConfigError(f"the {role} is a DH arm: give its capsule radii, one per link "
                              f"({arm.n} numbers, length unit)", path=path,
                              key=f"{role}.link_radius")
        return None
    if arm.dh is None:
        raise ConfigError(f"the {role}'s capsules are fitted to its robot file's collision "
                          "geometry; link_radius applies to DH arms and presets only",
                          path=path, key=f"{role}.link_radius")
    r = np.asarray(spec.link_radius, dtype=float) * length
    if r.shape != (arm.n,) or not (r > 0).all():
        raise ConfigError(f"needs {arm.n} positive radii (one per link), got "
                          f"{list(spec.link_radius)}", path=path, key=f"{role}.link_radius")
    return r


def _pose(spec: PoseSpec, length: float, angle: float) -> FloatArray:
    rpy = None if spec.rpy is None else np.asarray(spec.rpy, dtype=float) * angle
    return pose(np.asarray(spec.position, dtype=float) * length, rpy=rpy,
                rotation=spec.rotation)


__all__ = ["scene_of", "shape_of"]
