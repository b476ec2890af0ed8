"""Checks of an experiment file against its arms, made when the experiment is built.

Each raises :class:`~dualarm_qp.errors.ConfigError` naming the file and the key to change
(the command line exits 2):

* :func:`check_acceleration_limits`: with ``controller.acceleration_limits`` on, every
  joint of both arms has an acceleration limit, from the file (``qdd_max``, where
  ``.inf`` is an explicit "none") or from the arm (the PUMA 560 preset's); a URDF states
  none, so an arm from one needs ``qdd_max``;
* :func:`check_physics_tau_max`: ``physics.tau_max.<arm>`` holds one value or one per
  joint of the arm (checked here, so that ``run`` refuses what ``physics`` would);
* :func:`check_within_reach`: a pose an arm must reach (the start of the path, its
  waypoints, the follower's grasp) that lies absurdly close to the arm's base or far
  beyond its reach (:func:`~dualarm_qp.kinematics.reach.arm_reach`) points at the
  file's units: the message says that ``units.length`` may be wrong.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..errors import ConfigError
from ..kinematics.arm import SerialArm
from ..kinematics.reach import arm_reach
from .config import ExperimentConfig

FloatArray = NDArray[np.float64]

#: A target further than this many times the arm's reach from its base is far beyond it.
FAR_BEYOND_REACH = 10.0
#: A target closer than this share of the arm's reach to its base is absurdly close.
ABSURDLY_CLOSE = 0.01


def check_acceleration_limits(cfg: ExperimentConfig, arms: dict[str, SerialArm],
                              path: str) -> None:
    """Refuse acceleration limits on an arm that states none for some joint.

    Parameters
    ----------
    cfg : ExperimentConfig
        The file (``controller.acceleration_limits``, each arm's ``qdd_max``).
    arms : dict of str to SerialArm
        ``"leader"`` and ``"follower"``, with the file's limits applied.
    path : str
        The file, for the message.

    Raises
    ------
    ConfigError
        Key ``<role>.qdd_max``: acceleration limits on, the file gives no ``qdd_max``
        for the arm and the arm has none for some joint.
    """
    if not cfg.controller.acceleration_limits:
        return
    unit = f"{cfg.units.angle}/{cfg.units.time}^2"
    for role, arm in arms.items():
        if getattr(cfg, role).qdd_max is not None:
            continue  # the file's own choice; .inf there says "none" explicitly
        missing = np.flatnonzero(~np.isfinite(arm.qdd_max))
        if not missing.size:
            continue
        which = ("any joint" if missing.size == arm.n
                 else "joint" + ("s " if missing.size > 1 else " ")
                 + ", ".join(str(j + 1) for j in missing))
        raise ConfigError(
            f"controller.acceleration_limits is on, but the {role}'s arm ({arm.source}) "
            f"states no acceleration limit for {which} (a URDF or a DH table has none), so "
            f"its joints would not be limited: give {role}.qdd_max, one value per joint "
            f"({arm.n}, in {unit}; .inf leaves a joint unlimited on purpose), or turn "
            "controller.acceleration_limits off", path=path, key=f"{role}.qdd_max")


def check_physics_tau_max(cfg: ExperimentConfig, arms: dict[str, SerialArm],
                          path: str) -> None:
    """Refuse a ``physics.tau_max.<role>`` with neither 1 value nor one per joint.

    Raises
    ------
    ConfigError
        Key ``physics.tau_max.<role>``, with the valid counts.
    """
    for role, arm in arms.items():
        given = getattr(cfg.physics.tau_max, role)
        if given is not None and len(given) not in (1, arm.n):
            raise ConfigError(f"needs 1 value (every joint) or {arm.n} (one per {role} "
                              f"joint), got {len(given)}", path=path,
                              key=f"physics.tau_max.{role}", valid=("1", str(arm.n)))


def check_within_reach(cfg: ExperimentConfig, arm: SerialArm, role: str,
                       targets: list[tuple[str, FloatArray]], path: str) -> None:
    """Refuse targets absurdly close to the arm's base or far beyond its reach.

    A factor of 1000 (a length in metres read as millimetres, or the other way round)
    puts a target there, so the message points at ``units.length``.

    Parameters
    ----------
    cfg : ExperimentConfig
        The file (its ``units``).
    arm : SerialArm
        The arm, placed at its base.
    role : str
        ``"leader"`` or ``"follower"``.
    targets : list of (str, ndarray)
        What the arm's tool must reach (4x4 world poses [m]), each with the words that
        say where it comes from in the file (``"D(t0) H1^-1 (trajectory.start, object.H1)"``).
    path : str
        The file, for the message.

    Raises
    ------
    ConfigError
        Key ``units.length``: a target closer to the base than :data:`ABSURDLY_CLOSE`
        of the reach, or further than :data:`FAR_BEYOND_REACH` times it.
    """
    reach = arm_reach(arm)
    if not reach > 0.0:
        return
    base = arm.base[:3, 3]
    for what, T in targets:
        d = float(np.linalg.norm(np.asarray(T)[:3, 3] - base))
        if ABSURDLY_CLOSE * reach <= d <= FAR_BEYOND_REACH * reach:
            continue
        where = (f"{d / reach:.0f} times the arm's reach" if d > reach
                 else f"1/{reach / d:.0f} of the arm's reach" if d > 0.0 else "on it")
        unit = cfg.units.length
        given = "units" in cfg.model_fields_set and "length" in cfg.units.model_fields_set
        raise ConfigError(
            f"the {role}'s target {what} is {_length(d)} from the {role}'s base, {where} "
            f"({_length(reach)}): the file's units may be wrong; units.length is {unit}"
            f"{'' if given else ' (the default)'}: every length of the file is read in "
            f"{_UNIT_WORDS[unit]} (0.4 is 0.4 {unit}); give the lengths in {unit}, or set "
            "units.length to the unit they are in", path=path, key="units.length",
            valid=("m", "mm"))


#: The length units of a file, in words.
_UNIT_WORDS = {"m": "metres", "mm": "millimetres"}


def _length(d: float) -> str:
    """Return a distance [m] for a message: in mm below 1 m, else in m."""
    return f"{d * 1e3:.3g} mm" if d < 1.0 else f"{d:.3g} m"


__all__ = ["ABSURDLY_CLOSE", "FAR_BEYOND_REACH", "check_acceleration_limits",
           "check_physics_tau_max", "check_within_reach"]
