"""How far an arm can reach: a bound on the distance of its tool from its base.

Every link of a serial arm is rigid, so the distance between consecutive frames of
:meth:`~dualarm_qp.kinematics.SerialArm.link_frames` (the base, then the frame of each
joint) does not depend on the joints, nor does the distance from the last of them to
the tool. Their sum bounds the distance of the tool's origin from the base's origin at
any joints (the triangle inequality): :func:`arm_reach`. The bound is reached when
every link lines up; for a real arm it is its reach plus a few offsets.
"""

from __future__ import annotations

import numpy as np

from .arm import SerialArm


def arm_reach(arm: SerialArm) -> float:
    """Return the largest distance the arm's tool can have from its base [m].

    The sum of the lengths between consecutive link frames and from the last one to the
    tool (see the module docstring), computed at zero joints (any joints give the same).
    """
    q = np.zeros(arm.n)
    origins = np.vstack([arm.link_frames(q)[:, :3, 3], arm.fk(q)[:3, 3]])
    return float(np.linalg.norm(np.diff(origins, axis=0), axis=1).sum())


__all__ = ["arm_reach"]
