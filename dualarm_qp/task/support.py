"""Case 2: supporting the object without grasping it (paper Section 2, Eqs. 7-13).

Model (the paper's assumptions a-c, all vectors in object coordinates):

* the leader's hand, at ``r1`` [m] (the paper's ``r1^0``: the leader-hand origin seen
  from the object origin), can apply any force ``f_l`` [N] but no moment;
* the object's mass ``M`` [kg] is concentrated at its mass centre ``r_c`` [m]. The
  paper takes it at the origin of the object frame (implicitly: Eq. 7 has no moment of
  gravity about the origin), which is our default; for any other ``r_c`` every formula
  below holds with ``r1`` replaced by ``r1 - r_c`` in the moment (the equations written
  about the mass centre), see "Mass centre" below;
* the follower's hand at ``r2`` can only push along the surface normal,
  ``f_f = h a*(r2)`` with ``h > 0`` [N] (Eq. 10);
* only ``g~ = [g_x, 0, 0]`` of the gravity vector ``g = [g_x, g_y, g_z]`` [m/s^2] is
  balanced this way; ``M g_y`` and ``M g_z`` are assumed to be taken by the leader
  (the paper's note after Eq. 8, which neglects the moment of those components).

Equilibrium (Eqs. 7-8, with the symbols as corrected in docs/paper_corrections.md)::

    r1 x f_l + r2 x f_f = 0,        f_l + f_f + M g~ = 0.

Eliminating ``f_l`` gives Eq. 9, ``r1 x M g~ = (r2 - r1) x f_f``, which we confirm.
Write ``c = M r1 x g~`` [N m]. Eq. 9 is solvable only if ``c . a*(r2) = 0``; then

    r2 = r1 + (a* x c) / h + mu a*,     mu chosen so that phi(r2) = 0.

On a plane ``a* . r = d`` this is a straight line: ``r2(h) = r_inf + (a* x c) / h`` with
``r_inf`` the projection of ``r1`` on the plane (the limit ``h -> inf``). So the locus of
``r*`` as ``h`` varies is a half-line, and its unit tangent is the sliding vector
``s* = (a* x c) / |a* x c|`` (the direction in which ``r2`` moves as ``h`` decreases).

For the paper's worked example (``x = 0``, ``a* = [1, 0, 0]``, ``r1 = [0, r1y, -zmax]``)
this gives ``r* = [0, r1y (1 + M g_x / h), -zmax (1 + M g_x / h)]``. The printed Eq. 11
has the opposite sign on both ``M g_x / h`` terms; it satisfies Eq. 9 only with ``g~``
replaced by ``-g~``. Eqs. 12 and 13 hold either way (the locus is the same line). See
``docs/paper_corrections.md``, section "Case 2 support (Eqs. 9-13)".

Mass centre. With the mass centre at ``r_c`` (object coordinates), Eq. 7 about the
object origin gains the moment of the weight, ``r1 x f_l + r2 x f_f + r_c x M g~ = 0``;
eliminating ``f_l`` as before gives ``(r2 - r1) x f_f = M (r1 - r_c) x g~``: Eq. 9 written
about the mass centre. So ``c = M (r1 - r_c) x g~`` and the line is
``r2(h) = r_inf + (a* x c) / h`` with ``r_inf`` still the projection of ``r1`` on the
plane. With ``r_c = 0`` this is the paper's model exactly.

The line's place and direction depend on gravity only through the sign of ``g_x``:
``c = M g_x (r1 - r_c) x e_x``, so ``|g_x|`` scales the push ``h`` at every point of the
line (``h`` is proportional to ``|g_x|``) but does not move the line; a change of sign
of ``g_x`` reverses it (the pushing half-line is then on the other side of ``r_inf``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._validate import as_array
from ..errors import InvalidInputError, LimitsError
from .plane_bar import PlaneBar
from .plane_bar import line_box_range as _line_box_range
from .plane_bar import unit_vector as _unit
from .surface_base import as_bound as _as_bound
from .surface_base import as_sigma as _as_sigma

FloatArray = NDArray[np.float64]

__all__ = [
    "SupportSolution",
    "SupportLine",
    "gravity_tilde",
    "equilibrium_residual",
    "support_point",
    "support_line",
]


@dataclass(frozen=True)
class SupportSolution:
    """A static support equilibrium (Eqs. 7-10), object coordinates.

    Attributes
    ----------
    r2 : ndarray, shape (3,)
        Follower contact point [m].
    h : float
        Follower push magnitude [N] (``> 0`` for a physical support).
    normal : ndarray, shape (3,)
        Unit surface normal ``a*(r2)``.
    f_follower : ndarray, shape (3,)
        ``f_f = h a*(r2)`` [N].
    f_leader : ndarray, shape (3,)
        ``f_l = -f_f - M g~`` [N] (Eq. 8).
    residual : float
        Largest absolute residual of Eqs. 7 [N m] and 8 [N].
    """

    r2: FloatArray
    h: float
    normal: FloatArray
    f_follower: FloatArray
    f_leader: FloatArray
    residual: float


def _mass(mass: Any) -> float:
    m = _as_sigma(mass, "mass")
    if m <= 0.0:
        raise InvalidInputError(f"mass must be > 0 kg, got {m:g}")
    return m


def _push(h: Any) -> float:
    value = _as_sigma(h, "h")
    if value <= 0.0:
        raise InvalidInputError(f"h must be > 0 N (the follower can only push), got {value:g}")
    return value


def gravity_tilde(gravity: Any) -> FloatArray:
    """``g~ = [g_x, 0, 0]`` [m/s^2] from the gravity vector in object coordinates (Eq. 8)."""
    g = as_array(gravity, "gravity", (3,))
    return np.array([g[0], 0.0, 0.0])


def equilibrium_residual(
    r1: Any,
    r2: Any,
    f_leader: Any,
    f_follower: Any,
    *,
    mass: float,
    gravity: Any,
    mass_centre: Any = (0.0, 0.0, 0.0),
) -> FloatArray:
    """Residual of Eqs. 7-8: ``[r1 x f_l + r2 x f_f + r_c x M g~; f_l + f_f + M g~]``.

    In [N m; N], moments about the object origin (``r_c = 0``: the paper's Eq. 7).

    Parameters
    ----------
    r1, r2 : array_like, shape (3,)
        Leader and follower contact points [m], object coordinates.
    f_leader, f_follower : array_like, shape (3,)
        Forces applied to the object by the leader and the follower [N].
    mass : float, keyword-only
        Object mass [kg].
    gravity : array_like, shape (3,), keyword-only
        Gravity in object coordinates [m/s^2]; only ``g_x`` is used.
    mass_centre : array_like, shape (3,), keyword-only
        Mass centre ``r_c`` [m], object coordinates; default the origin.
    """
    a1 = as_array(r1, "r1", (3,))
    a2 = as_array(r2, "r2", (3,))
    fl = as_array(f_leader, "f_leader", (3,))
    ff = as_array(f_follower, "f_follower", (3,))
    rc = as_array(mass_centre, "mass_centre", (3,))
    weight = _mass(mass) * gravity_tilde(gravity)
    out = np.empty(6)
    out[:3] = np.cross(a1, fl) + np.cross(a2, ff) + np.cross(rc, weight)
    out[3:] = fl + ff + weight
    return out


def _solution(
    r1: FloatArray,
    r2: FloatArray,
    h: float,
    a: FloatArray,
    mass: float,
    gt: FloatArray,
    rc: FloatArray | None = None,
) -> SupportSolution:
    ff = h * a
    fl = -ff - mass * gt
    moment = np.cross(r1, fl) + np.cross(r2, ff)
    if rc is not None:
        moment = moment + np.cross(rc, mass * gt)
    res = np.concatenate([moment, fl + ff + mass * gt])
    return SupportSolution(
        r2=r2,
        h=h,
        normal=a.copy(),
        f_follower=ff,
        f_leader=fl,
        residual=float(np.max(np.abs(res))),
    )


def _moment(r1: FloatArray, mass: float, gt: FloatArray, a: FloatArray) -> FloatArray:
    """``c = M r1 x g~`` [N m], checking the solvability condition ``c . a* = 0``.

    ``r1`` is the leader-hand origin seen from the mass centre (``r1 - r_c``).
    """
    c = mass * np.cross(r1, gt)
    scale = max(float(np.linalg.norm(c)), 1e-300)
    if abs(float(c @ a)) > 1e-9 * scale:
        raise InvalidInputError(
            "no support equilibrium: the moment M r1 x g~ has a component "
            f"{float(c @ a):.3g} N m along the surface normal, which a normal push "
            "cannot balance (Eq. 9 needs (M r1 x g~) . a* = 0)"
        )
    return c


def support_point(
    r1: Any,
    *,
    mass: float,
    gravity: Any,
    h: float,
    normal: Any = (1.0, 0.0, 0.0),
    offset: float = 0.0,
    mass_centre: Any = (0.0, 0.0, 0.0),
) -> SupportSolution:
    """Follower contact point on the plane ``a* . r = offset`` for a push ``h`` (Eq. 9).

    ``r2 = r_inf + (a* x c) / h`` with ``c = M r1 x g~`` and ``r_inf = r1 - (a*.r1 -
    offset) a*``. For the paper's example this is the corrected Eq. 11 (see module
    docstring).

    Parameters
    ----------
    r1 : array_like, shape (3,)
        Leader-hand origin in object coordinates [m] (the paper's ``r1^0``).
    mass : float, keyword-only
        Object mass [kg], > 0.
    gravity : array_like, shape (3,), keyword-only
        Gravity in object coordinates [m/s^2]; only ``g_x`` is used.
    h : float, keyword-only
        Follower push magnitude [N], > 0.
    normal : array_like, shape (3,), keyword-only
        Plane normal ``a*`` (normalised here); the follower pushes along ``+a*``.
    offset : float, keyword-only
        Plane offset ``d`` [m] in ``a* . r = d``.
    mass_centre : array_like, shape (3,), keyword-only
        Mass centre ``r_c`` [m], object coordinates; default the origin (the paper's).

    Raises
    ------
    InvalidInputError
        Non-positive mass or ``h``, or no equilibrium (``c . a* != 0``).
    """
    a1 = as_array(r1, "r1", (3,))
    rc = as_array(mass_centre, "mass_centre", (3,))
    m, hh = _mass(mass), _push(h)
    gt = gravity_tilde(gravity)
    a = _unit(normal, "normal")
    d = _as_sigma(offset, "offset")
    c = _moment(a1 - rc, m, gt, a)
    r_inf = a1 - (float(a @ a1) - d) * a
    r2 = r_inf + np.cross(a, c) / hh
    return _solution(a1, r2, hh, a, m, gt, rc)


class SupportLine(PlaneBar):
    """The locus of Case 2 support points on a plane, usable as a sliding path.

    A :class:`~dualarm_qp.task.surfaces.PlaneBar` whose line is
    ``r2(h) = r_inf + (a* x c) / h`` (``h > 0``), with sliding vector
    ``s* = (a* x c) / |a* x c|`` (Eq. 13 for the paper's example) and ``sigma`` measured
    from the foot of the perpendicular from the object origin onto the line (with the
    mass centre at the origin, the paper's case, that is the mass centre's foot). Build
    it with :func:`support_line`.

    Attributes
    ----------
    r1 : ndarray, shape (3,)
        Leader-hand origin [m], object coordinates.
    mass : float
        Object mass [kg].
    mass_centre : ndarray, shape (3,)
        Mass centre ``r_c`` [m], object coordinates.
    g_tilde : ndarray, shape (3,)
        ``[g_x, 0, 0]`` [m/s^2].
    moment : ndarray, shape (3,)
        ``c = M (r1 - r_c) x g~`` [N m].
    r_inf : ndarray, shape (3,)
        Limit of ``r2`` as ``h -> inf`` [m].
    sigma_inf : float
        Its path parameter [m]; physical supports have ``sigma > sigma_inf``.
    """

    def __init__(
        self,
        *,
        r1: FloatArray,
        mass: float,
        g_tilde: FloatArray,
        normal: FloatArray,
        offset: float,
        r_min: Any,
        r_max: Any,
        h_max: float | None,
        mass_centre: FloatArray | None = None,
    ) -> None:
        a = _unit(normal, "normal")
        rc = np.zeros(3) if mass_centre is None else mass_centre
        c = _moment(r1 - rc, mass, g_tilde, a)
        axc = np.cross(a, c)
        lever = float(np.linalg.norm(axc))
        if lever < 1e-12 * max(1.0, mass * float(np.linalg.norm(g_tilde))):
            raise InvalidInputError(
                "degenerate support: M (r1 - r_c) x g~ = 0 (g_x = 0, or the leader's hand "
                "and the mass centre on one line along x), so the support point does not "
                "move with h and there is no sliding line"
            )
        s = axc / lever
        r_inf = r1 - (float(a @ r1) - offset) * a
        origin = r_inf - float(r_inf @ s) * s
        sigma_inf = float(s @ (r_inf - origin))
        lo_box, hi_box = _as_bound(r_min, "r_min"), _as_bound(r_max, "r_max")
        lo, hi = _line_box_range(origin, s, lo_box, hi_box)
        lo = max(lo, sigma_inf if h_max is None else sigma_inf + lever / _push(h_max))
        if lo > hi or hi <= sigma_inf:  # only the leader's hand, where h is infinite
            raise InvalidInputError(
                "no support point with h > 0 (and h <= h_max) inside the box r_min/r_max"
            )
        if not math.isfinite(hi):
            raise LimitsError(
                "the support line is unbounded inside the box r_min/r_max on the h > 0 "
                "side; give finite bounds along it"
            )
        super().__init__(
            r_min=lo_box,
            r_max=hi_box,
            origin=origin,
            sliding=s,
            normal=a,
            sigma_min=lo,
            sigma_max=hi,
        )
        self.r1 = r1.copy()
        self.mass = mass
        self.mass_centre = rc.copy()
        self.g_tilde = g_tilde.copy()
        self.moment = c
        self.r_inf = r_inf
        self.sigma_inf = sigma_inf
        self._lever = lever

    def force(self, sigma: float) -> float:
        """Follower push ``h`` [N] that holds the object with the contact at ``sigma``.

        ``h = |a* x c| / (sigma - sigma_inf)``: ``inf`` at ``sigma_inf`` and negative
        (no pushing support) below it.
        """
        ds = _as_sigma(sigma) - self.sigma_inf
        return math.inf if ds == 0.0 else self._lever / ds

    def sigma_at(self, h: float) -> float:
        """Path parameter [m] of the support point for a push ``h`` [N] (> 0)."""
        return self.sigma_inf + self._lever / _push(h)

    def solution(self, sigma: float) -> SupportSolution:
        """Full equilibrium (forces of both hands) with the contact at ``sigma``."""
        h = self.force(sigma)
        if not (0.0 < h < math.inf):
            raise InvalidInputError(
                f"sigma = {sigma:g} m needs h = {h:g} N: no pushing support there "
                f"(physical supports have sigma > {self.sigma_inf:g} m)"
            )
        return _solution(self.r1, self.point(sigma), h, self._a, self.mass, self.g_tilde,
                         self.mass_centre)


def support_line(
    r1: Any,
    *,
    mass: float,
    gravity: Any,
    normal: Any = (1.0, 0.0, 0.0),
    offset: float = 0.0,
    r_min: Any = (-math.inf, -math.inf, -math.inf),
    r_max: Any = (math.inf, math.inf, math.inf),
    h_max: float | None = None,
    mass_centre: Any = (0.0, 0.0, 0.0),
) -> SupportLine:
    """Sliding path of Case 2 support points on the plane ``a* . r = offset``.

    Parameters
    ----------
    r1 : array_like, shape (3,)
        Leader-hand origin in object coordinates [m].
    mass : float, keyword-only
        Object mass [kg].
    gravity : array_like, shape (3,), keyword-only
        Gravity in object coordinates [m/s^2]; only ``g_x`` is used.
    normal, offset : keyword-only
        The plane ``a* . r = offset`` [m]; the follower pushes along ``+a*``.
    r_min, r_max : array_like, shape (3,), keyword-only
        Box of Eq. 3 on the surface [m]; must bound the line on the ``h > 0`` side.
    h_max : float or None, keyword-only
        Largest admissible push [N]; sets ``sigma_min``. Without it ``sigma_min`` is at
        least ``sigma_inf`` (where ``h`` would be infinite).
    mass_centre : array_like, shape (3,), keyword-only
        Mass centre ``r_c`` [m], object coordinates; default the origin (the paper's).

    Returns
    -------
    SupportLine

    Raises
    ------
    InvalidInputError
        No equilibrium, degenerate moment, or no ``h > 0`` support inside the box.
    LimitsError
        The box does not bound the line.
    """
    return SupportLine(
        r1=as_array(r1, "r1", (3,)),
        mass=_mass(mass),
        g_tilde=gravity_tilde(gravity),
        normal=as_array(normal, "normal", (3,)),
        offset=_as_sigma(offset, "offset"),
        r_min=r_min,
        r_max=r_max,
        h_max=h_max,
        mass_centre=as_array(mass_centre, "mass_centre", (3,)),
    )
