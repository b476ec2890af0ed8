"""The arms of an experiment file: the model (preset, DH table, URDF chain), limits, torques.

Each arm is a :class:`~dualarm_qp.kinematics.arm.SerialArm` in SI units, its file limits
checked (a range that no joint can reach, crossed limits, a limit that is not
positive) with errors naming the key. The follower's base may still be recovered from
the start (:mod:`.setup_initial`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ..errors import ConfigError
from ..kinematics.arm import DHTable, SerialArm
from ..kinematics.puma560 import puma560
from ..kinematics.robots import EXAMPLE_ROBOTS, RobotModelError, example_robot_arm, urdf_arm
from ..task.torques import torque_limits_of
from .config import ArmSpec, ExperimentConfig
from .setup_checks import check_acceleration_limits, check_physics_tau_max
from .setup_values import Scales, at_key, file_pose, required, vector

FloatArray = NDArray[np.float64]


def arms_of(cfg: ExperimentConfig, sc: Scales, path: str) -> tuple[SerialArm, SerialArm]:
    """Return the leader (on its base) and the follower (its base not yet placed), checked.

    Each arm has at least the joints to carry the object along a 6-DoF path (the
    leader 6, the follower 5 with its sliding grasp), and the limits that the controller
    section and the physics section ask for (:mod:`.setup_checks`).
    """
    if cfg.leader.base == "auto":
        raise ConfigError("'auto' is only supported for the follower's base", path=path,
                          key="leader.base")
    with at_key("leader", path):
        leader = arm_of(cfg.leader, sc, "leader", file_pose(cfg.leader.base, sc), path)
    with at_key("follower", path):
        follower = arm_of(cfg.follower, sc, "follower", None, path)
    for role, arm, least in (("leader", leader, 6), ("follower", follower, 5)):
        if arm.n < least:
            raise ConfigError(f"the {role} has {arm.n} joints; it needs at least {least} "
                              "to carry the object along a 6-DoF path", path=path,
                              key=model_key(getattr(cfg, role), role))
    check_acceleration_limits(cfg, {"leader": leader, "follower": follower}, path)
    check_physics_tau_max(cfg, {"leader": leader, "follower": follower}, path)
    return leader, follower


def arm_of(spec: ArmSpec, sc: Scales, role: str, base: FloatArray | None, path: str) -> SerialArm:
    """Return the arm ``role`` of the file on ``base``, with the file's limits over the model's."""
    tool = None if spec.tool is None else file_pose(spec.tool, sc)
    if spec.preset == "puma560":
        arm = puma560(base=base, tool=tool, name=f"{role} puma560")
    elif spec.dh is not None:
        rows = np.asarray(spec.dh.rows, dtype=float)
        scale = np.array([sc.length, sc.angle, sc.length, sc.angle][: rows.shape[1]])
        arm = SerialArm(DHTable.from_rows(rows * scale, spec.dh.convention), base=base,
                        tool=tool, name=role)
    else:
        arm = _robot_arm(spec, role, base, tool, path)
    n = arm.n
    q_min = vector(spec.q_min, sc.angle, n, f"{role}.q_min", path)
    q_max = vector(spec.q_max, sc.angle, n, f"{role}.q_max", path)
    qd_max = vector(spec.qd_max, sc.angle / sc.time, n, f"{role}.qd_max", path)
    qdd_max = vector(spec.qdd_max, sc.angle / sc.time**2, n, f"{role}.qdd_max", path)
    if q_min is None and q_max is None and qd_max is None and qdd_max is None:
        return arm
    lo = arm.q_min if q_min is None else q_min
    hi = arm.q_max if q_max is None else q_max
    for key, values, wrong in (("q_min", q_min, np.inf), ("q_max", q_max, -np.inf)):
        if values is not None and (values == wrong).any():
            i = int(np.flatnonzero(values == wrong)[0])
            raise ConfigError(f"joint {i + 1}: {key} is {wrong:+g}, which no joint can reach "
                              f"(an open side is {-wrong:+g})", path=path,
                              key=f"{role}.{key}")
    crossed = np.flatnonzero(lo > hi)
    if crossed.size:
        i = int(crossed[0])
        raise ConfigError(f"joint {i + 1}: q_min ({lo[i] / sc.angle:g}) is above q_max "
                          f"({hi[i] / sc.angle:g})", path=path,
                          key=f"{role}.q_min" if q_min is not None else f"{role}.q_max")
    for key, values, unit in (("qd_max", qd_max, sc.angle / sc.time),
                              ("qdd_max", qdd_max, sc.angle / sc.time**2)):
        if values is not None and not (values > 0).all():
            i = int(np.flatnonzero(~(values > 0))[0])
            what = "a speed" if key == "qd_max" else "an acceleration"
            raise ConfigError(f"joint {i + 1}: {what} limit must be > 0, got "
                              f"{values[i] / unit:g}", path=path, key=f"{role}.{key}")
    return arm.with_limits(q_min, q_max, qd_max, qdd_max)


def tau_max_of(spec: ArmSpec, arm: SerialArm, role: str, on: bool, path: str
             ) -> FloatArray | None:
    """Return the arm's ``tau_max`` [N m] as given (checked), or None for the default.

    With ``controller.torque_limits`` on, an arm without ``tau_max`` must have a URDF
    ``effort`` (the default); a DH arm or preset has none.
    """
    key = f"{role}.tau_max"
    given = vector(spec.tau_max, 1.0, arm.n, key, path)
    if given is not None:
        bad = np.flatnonzero(~(given > 0.0))
        if bad.size:
            j = int(bad[0])
            raise ConfigError(f"joint {j + 1}: a torque limit must be > 0 N m (.inf: no "
                              f"limit), got {given[j]:g}", path=path, key=key)
    if on:
        with at_key(key, path):
            torque_limits_of(arm, given, role)
    return given


def _robot_arm(spec: ArmSpec, role: str, base: FloatArray | None, tool: FloatArray | None,
               path: str) -> SerialArm:
    """One chain of a URDF (``urdf``) or of an example-robot-data robot (``example_robot``).

    Joint ranges and speed limits are the URDF's; the file's ``q_min`` / ``q_max`` /
    ``qd_max`` override them (see :func:`arm_of`).
    """
    try:
        if spec.urdf is not None:
            key = f"{role}.urdf"
            file = Path(spec.urdf.file)
            if not file.is_absolute():  # relative to the experiment file's folder
                file = Path(path).parent / file
            return urdf_arm(file, spec.urdf.root, spec.urdf.tip, base=base, tool=tool,
                            name=f"{role} {file.stem}")
        robot = required(spec.example_robot, f"{role}.example_robot", path)
        key = f"{role}.example_robot"
        return example_robot_arm(robot.name, robot.root, robot.tip, base=base, tool=tool,
                                 name=f"{role} {robot.name}")
    except RobotModelError as err:
        field = err.field if err.field in ("file", "name", "root", "tip") else None
        known = err.field == "name" and "unknown robot" in str(err)
        raise ConfigError(str(err), path=path, key=f"{key}.{field}" if field else key,
                          valid=sorted(EXAMPLE_ROBOTS) if known else ()) from None


def model_key(spec: ArmSpec, role: str) -> str:
    """Return the key of ``role``'s arm model, for messages (``leader.dh.rows``, ...)."""
    key = spec.model_key
    return f"{role}.{key}.rows" if key == "dh" else f"{role}.{key}"


__all__ = ["arm_of", "arms_of", "model_key", "tau_max_of"]
