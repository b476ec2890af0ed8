"""How the follower holds the object: a grasp (Case 1) or a support (Case 2).

With a grasp the follower's sliding path is a fixed curve on the object surface. With a
support (the paper's Case 2, Eqs. 7-13) the follower's hand only pushes along the
surface normal ``a*``, and the path is the *support line*: the points where such a push
``h > 0`` together with a pure force of the leader's hand holds the object's weight
(:class:`~dualarm_qp.task.support.SupportLine`). That line is computed from gravity in
object coordinates, ``g_o = R_world_object^T g_world``, so it belongs to the object's
current orientation. :class:`SupportContact` holds what does not change (mass, mass
centre, world gravity, the plane and its box, the leader's hand on the object) and
gives the line for any orientation; the step builder asks for it once per step and
keeps it frozen within the step (see docs/support.md).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._compiled import kernel
from .._validate import as_array, as_pose
from ..errors import InvalidInputError, SupportLostError
from .support import SupportLine, support_line
from .surfaces import PlaneBar

FloatArray = NDArray[np.float64]

__all__ = ["SupportContact"]

#: ``|g_x|`` below this share of ``|g|`` counts as no gravity along the push: the line
#: is then degenerate (every push would have to be infinite).
GRAVITY_ALONG_PUSH_MIN = 1e-9


class SupportContact:
    """The follower supports the object without grasping it (Case 2), on a plane.

    Parameters
    ----------
    mass : float, keyword-only
        Object mass ``M`` [kg], > 0.
    mass_centre : array_like, shape (3,), keyword-only
        Mass centre ``r_c`` [m], object coordinates.
    gravity : array_like, shape (3,), keyword-only
        Gravity in the world frame [m/s^2], non-zero.
    plane : PlaneBar, keyword-only
        The supporting face: its plane ``a* . (r - origin) = 0`` (the follower pushes
        along ``+a*``) and its box ``r_min`` / ``r_max`` [m] (Eq. 3).
    H1 : ndarray, shape (4, 4), keyword-only
        ``T_leader_object`` of the leader's rigid grasp [m]; the leader's hand origin in
        object coordinates (the paper's ``r1^0``) is the translation of ``H1^-1``.

    Attributes
    ----------
    mass : float
        [kg].
    mass_centre : ndarray, shape (3,)
        [m], object coordinates.
    gravity : ndarray, shape (3,)
        [m/s^2], world frame.
    r1 : ndarray, shape (3,)
        Leader's hand origin [m], object coordinates.
    plane : PlaneBar
        The supporting face.

    Raises
    ------
    InvalidInputError
        A non-positive mass, zero gravity, or a surface that is not a :class:`PlaneBar`.
    """

    def __init__(self, *, mass: float, mass_centre: Any, gravity: Any, plane: PlaneBar,
                 H1: Any) -> None:
        m = float(mass)
        if not (math.isfinite(m) and m > 0.0):
            raise InvalidInputError(f"mass must be a finite number > 0 kg, got {mass!r}")
        g = as_array(gravity, "gravity", (3,)).copy()
        if not float(np.linalg.norm(g)) > 0.0:
            raise InvalidInputError("gravity must be a non-zero vector [m/s^2]")
        if not isinstance(plane, PlaneBar):
            raise InvalidInputError("a support needs a plane surface (PlaneBar), got "
                                    f"{type(plane).__name__}")
        T_leader_object = as_pose(H1, "H1")
        R = T_leader_object[:3, :3]
        self.mass = m
        self.mass_centre = as_array(mass_centre, "mass_centre", (3,)).copy()
        self.gravity = g
        self.r1 = -R.T @ T_leader_object[:3, 3]
        self.plane = plane
        self._a = plane.normal(0.0)
        self._offset = float(self._a @ plane.origin)

    def gravity_in_object(self, R_world_object: Any) -> FloatArray:
        """Gravity in object coordinates, ``g_o = R_world_object^T g_world`` [m/s^2]."""
        R = as_array(R_world_object, "R_world_object", (3, 3))
        return R.T @ self.gravity

    def line(self, R_world_object: Any) -> SupportLine:
        """Return the support line for the object's orientation ``R_world_object``.

        The follower's sliding path (object coordinates): the points of the plane where a
        push ``h > 0`` along ``a*`` balances the weight with the leader (Eqs. 7-10 about
        the mass centre), restricted to the box and to ``h > 0``.

        Raises
        ------
        InvalidInputError
            Gravity has no component along the push (``g_x = 0`` in object coordinates),
            the moment cannot be balanced by a normal push, or no point of the box holds
            the object with ``h > 0`` (the follower would have to pull).
        """
        g_o = self.gravity_in_object(R_world_object)
        if abs(float(g_o[0])) <= GRAVITY_ALONG_PUSH_MIN * float(np.linalg.norm(g_o)):
            raise SupportLostError(
                "support lost: gravity in object coordinates "
                f"[{g_o[0]:.4g}, {g_o[1]:.4g}, {g_o[2]:.4g}] m/s^2 has no component along the "
                "object's x axis, so a push along the surface normal carries none of the "
                "weight")
        plane = self.plane
        try:
            return support_line(self.r1, mass=self.mass, gravity=g_o, normal=self._a,
                                offset=self._offset, r_min=plane.r_min, r_max=plane.r_max,
                                mass_centre=self.mass_centre)
        except InvalidInputError as err:
            raise SupportLostError(
                "support lost for gravity in object coordinates "
                f"[{g_o[0]:.4g}, {g_o[1]:.4g}, {g_o[2]:.4g}] m/s^2: {err}") from None

    def compiled(self) -> Any:
        """Return the kernel's form of this support (``kernel.SupportPlane``).

        Its ``line(R_world_object)`` is :meth:`line`'s line, computed by the kernel
        (``src/kernel/support_line.cpp``): what the step builder asks each step. Where it
        finds none (``held`` False), :meth:`line` says why.
        """
        plane = self.plane
        return kernel.SupportPlane(self.mass, self.mass_centre, self.gravity, self.r1,
                                   self._a, self._offset, plane.r_min, plane.r_max,
                                   GRAVITY_ALONG_PUSH_MIN)

    def force(self, line: SupportLine, sigma: float) -> float:
        """Push ``h`` [N] on ``line`` at the grasp coordinate ``sigma`` [m], checked.

        Raises
        ------
        InvalidInputError
            ``h <= 0`` or infinite there: the follower would have to pull (or push
            infinitely hard, at the leader's hand).
        """
        h = line.force(sigma)
        if not (0.0 < h < math.inf):
            raise SupportLostError(
                f"support lost at grasp {sigma:.6g} m: holding the object there needs a "
                f"follower force h = {h:.4g} N along the surface normal; a support can only "
                f"push (h > 0, finite), which needs grasp > {line.sigma_inf:.6g} m")
        return h

    def __repr__(self) -> str:
        return (f"SupportContact(mass={self.mass:g} kg, mass_centre={self.mass_centre.tolist()}"
                f" m, gravity={self.gravity.tolist()} m/s^2)")
