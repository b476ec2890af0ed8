"""Case 2: each step's support line, placed before the step's kinematics.

With a supporting follower (:class:`~dualarm_qp.task.contact.SupportContact`) the
follower's path is the support line of the object's current orientation
(:mod:`dualarm_qp.task.support` derives it; docs/support.md). Each step, before the
step's kinematics, :meth:`SupportPlacement.place`

1. reads the object's orientation from the carried-object model at the step's joints
   (one kernel call: the object frame does not depend on the follower's grasp);
2. computes the line for it in the kernel (``kernel.SupportPlane``,
   ``src/kernel/support_line.cpp``: the equations of
   :class:`~dualarm_qp.task.support.SupportLine`);
3. refuses a line that reversed since the previous step (gravity's component along the
   push changed sign), re-places the follower's grasp joint
   (:meth:`~dualarm_qp.task.carry.CarryModel.place_follower`) when the line moved by more
   than ``1e-12`` m, and gives the follower's push ``h`` at the grasp.

Where the kernel finds no support (no line with ``h > 0``, or ``h <= 0`` at the grasp),
the contact's own Python computation says why (:meth:`SupportContact.line`,
:meth:`SupportContact.force` raise :class:`~dualarm_qp.errors.SupportLostError`). The
Python :class:`~dualarm_qp.task.support.SupportLine` of a step is made only when read
(:attr:`StepContext.surfaces <dualarm_qp.step.context.StepContext.surfaces>`).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import SupportLostError
from ..task.carry import CarryModel
from ..task.contact import SupportContact
from ..task.support import SupportLine
from ..task.surfaces import GraspSurface

FloatArray = NDArray[np.float64]

#: The line moved (the follower's grasp joint is re-placed) when its pose at ``sigma = 0``
#: changed by more than this [m] (any entry).
MOVED_ATOL = 1e-12


class SupportPlacement:
    """Places the follower of a Case 2 support on each step's support line.

    Parameters
    ----------
    contact : SupportContact
        The support (mass, gravity, the plane and its box, the leader's hand).
    carry : CarryModel
        The carried-object model whose follower grasp joint follows the line.
    surface : GraspSurface
        The follower's path the model starts on (the support line at the start).
    """

    def __init__(self, contact: SupportContact, carry: CarryModel,
                 surface: GraspSurface) -> None:
        self.contact = contact
        self.carry = carry
        self._frame = (carry.frames[1],)
        # The previous step's line: its pose at sigma = 0 and, for a support line, its
        # direction (a line that reverses is refused).
        self._pose = surface.pose(0.0)
        self._direction = surface.tangent(0.0) if isinstance(surface, SupportLine) else None
        self._plane = self.contact.compiled()  # a kernel.SupportPlane (it pickles itself)

    def place(self, q_carry: FloatArray, sigma: float) -> tuple[Any, float, FloatArray]:
        """Put the follower on the support line at the model's joints ``q_carry``.

        Returns
        -------
        line : kernel.SupportLine
            The line (object coordinates): its origin, direction and grasp range.
        h : float
            The follower's push [N] at ``sigma`` [m].
        R : ndarray, shape (3, 3)
            The object's orientation the line is for.

        Raises
        ------
        SupportLostError
            No pushing support for this orientation, the line reversed, or ``h <= 0``
            (or infinite) at ``sigma``.
        """
        T = np.empty((4, 4))
        self.carry.chain.poses(q_carry, self._frame, T)
        R = T[:3, :3]
        contact = self.contact
        line = self._plane.line(R)
        if not line.held:
            contact.line(R)  # raises, saying why
            raise SupportLostError("support lost: no support line with a push h > 0 inside "
                                   "the box at this orientation")
        direction = line.direction
        if self._direction is not None and float(direction @ self._direction) < 0.0:
            raise SupportLostError(
                "support lost: the support line reversed (gravity's component along the "
                "surface normal changed sign), so the follower would have to pull")
        pose = line.pose0
        if not (np.abs(pose - self._pose) <= MOVED_ATOL).all():
            self.carry.place_follower(contact.line(R))
        self._pose, self._direction = pose.copy(), direction.copy()
        h = line.push(sigma)
        if not 0.0 < h < math.inf:
            contact.force(contact.line(R), sigma)  # raises, saying where
            raise SupportLostError(f"support lost at grasp {sigma:.6g} m: h = {h:.4g} N")
        return line, h, R


__all__ = ["MOVED_ATOL", "SupportPlacement"]
