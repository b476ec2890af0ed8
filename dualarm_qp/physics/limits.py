"""The joint torque limits of the physics check: the file's, else the arm's, else the model's."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidInputError
from ..task.scene import DualArmTask
from ..task.torques import model_effort
from .settings import PhysicsSettings

FloatArray = NDArray[np.float64]


def torque_limits(task: DualArmTask, settings: PhysicsSettings,
                  arm_tau_max: dict[str, FloatArray | None] | None = None
                  ) -> dict[str, FloatArray]:
    """Each arm's joint torque limits [N m].

    The ``physics.tau_max`` of the file, else the arm's own ``tau_max`` (``arm_tau_max``:
    the controller's, :class:`~dualarm_qp.step.options.StepOptions`), else the model's: a
    URDF's ``effort``; a joint without one (a DH arm) gets inf. A given limit is one
    value (every joint) or one per joint; ``inf`` leaves a joint unlimited.

    Raises
    ------
    InvalidInputError
        A given limit with another count.
    """
    out = {}
    for role, arm in (("leader", task.leader), ("follower", task.follower)):
        given = None if settings.tau_max is None else settings.tau_max.get(role)
        if given is None and arm_tau_max is not None:
            given = arm_tau_max.get(role)
        if given is not None:
            given = np.asarray(given, dtype=float).ravel()
            if given.size not in (1, arm.n):
                raise InvalidInputError(f"{role}: torque limits need 1 value or {arm.n} (one "
                                        f"per joint), got {given.size}")
            lim = np.broadcast_to(given, (arm.n,)).copy()
        else:
            lim = model_effort(arm)
        out[role] = lim
    return out


__all__ = ["torque_limits"]
