"""The paper's Case 1 construction (Steps 1-4): the grasp pose from a surface and a centre line."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._validate import as_array
from ..errors import InvalidInputError, NonFiniteError
from .surface_base import as_sigma, frame_from

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class CenterLine:
    """Centre line ``x = x(z), y = y(z)`` of the projected surface (paper Step 2).

    Attributes
    ----------
    x, y : callable float -> float
        Object-frame ``x`` and ``y`` [m] of the centre line at height ``z`` [m].
    dx_dz, dy_dz : callable float -> float
        Their derivatives ``alpha = dx/dz`` and ``beta = dy/dz`` (dimensionless).
    """

    x: Callable[[float], float]
    y: Callable[[float], float]
    dx_dz: Callable[[float], float]
    dy_dz: Callable[[float], float]


def case1_pose(
    phi: Callable[[FloatArray], float] | None,
    line: CenterLine,
    z: float,
    *,
    grad_phi: Callable[[FloatArray], Any] | None = None,
    fd_step: float = 1e-6,
) -> FloatArray:
    """Supporting pose ``H2(r*)`` of Case 1 (paper Steps 1-4, Eqs. 3-6 and 16).

    With ``r* = [x(z), y(z), z]`` (Step 2):

    * ``s* = [alpha, beta, 1] / sqrt(1 + alpha^2 + beta^2)`` (Eq. 4),
    * ``a* = grad phi(r*) / |grad phi(r*)|`` (Eq. 5),
    * ``n* = a* x s*`` (Eq. 6).

    The paper assumes ``s*`` is tangent to the surface. That holds when the centre
    line lies on the surface, but a centre line of a *projection* (Step 1) need not,
    and then ``s* . a* != 0`` and ``[s*, n*, a*]`` is not a rotation. We therefore
    project ``s*`` onto the tangent plane, ``s* <- (s* - (s*.a*) a*)``, and renormalise
    (a no-op when ``s*`` is already tangent). The result is always a proper rotation.

    Parameters
    ----------
    phi : callable or None
        Surface function ``phi(r)`` of Eq. 3 (object coordinates, [m]); used only to
        take a central-difference gradient when ``grad_phi`` is not given.
    line : CenterLine
        The centre line and its slopes.
    z : float
        Object-frame height ``r*_z`` [m] at which to evaluate.
    grad_phi : callable, optional, keyword-only
        Exact gradient of ``phi``; preferred over differencing.
    fd_step : float, keyword-only
        Step [m] of the central difference when ``grad_phi`` is None.

    Returns
    -------
    ndarray, shape (4, 4)
        ``H2 = [s*, n*, a*, r*; 0 0 0 1]``, the follower-hand pose in the object frame.

    Raises
    ------
    InvalidInputError
        Neither ``phi`` nor ``grad_phi`` given, ``grad phi(r*) = 0``, or the centre line
        is normal to the surface (no tangent direction left after projection).
    """
    zz = as_sigma(z, "z")
    r = np.array([float(line.x(zz)), float(line.y(zz)), zz])
    alpha, beta = float(line.dx_dz(zz)), float(line.dy_dz(zz))
    if not (np.all(np.isfinite(r)) and math.isfinite(alpha) and math.isfinite(beta)):
        raise NonFiniteError("center line at z")
    if grad_phi is not None:
        g = as_array(grad_phi(r), "grad_phi(r*)", (3,))
    elif phi is not None:
        g = np.empty(3)
        for i in range(3):
            e = np.zeros(3)
            e[i] = fd_step
            g[i] = (float(phi(r + e)) - float(phi(r - e))) / (2.0 * fd_step)
    else:
        raise InvalidInputError("case1_pose needs phi or grad_phi")
    gn = float(np.linalg.norm(g))
    if gn < 1e-12:
        raise InvalidInputError(f"grad phi vanishes at r* = {r}: no surface normal (Eq. 5)")
    a = g / gn
    s = np.array([alpha, beta, 1.0]) / math.sqrt(1.0 + alpha * alpha + beta * beta)
    s = s - float(s @ a) * a
    sn = float(np.linalg.norm(s))
    if sn < 1e-9:
        raise InvalidInputError(
            f"the centre line is normal to the surface at r* = {r}: no sliding direction"
        )
    H = np.eye(4)
    H[:3, :3] = frame_from(s / sn, a)
    H[:3, 3] = r
    return H


__all__ = ["CenterLine", "case1_pose"]
