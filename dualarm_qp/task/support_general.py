"""Case 2 on any surface: the support point solved numerically, offline (Eqs. 9-10).

On a plane the support locus is a straight line, computed exactly by
:func:`~.support.support_line`; on a curved surface :func:`solve_support` finds the
support point for a push ``h`` by Gauss-Newton and :func:`support_sliding_vector` the
locus' tangent there. Meant for planning a support, not for a step (see :mod:`.support`
for the model and the symbols).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from .._validate import as_array
from ..errors import InvalidInputError
from .support import SupportSolution, _mass, _push, _solution, gravity_tilde

FloatArray = NDArray[np.float64]


class ImplicitSurface(Protocol):
    """Anything with an implicit surface ``phi`` and its gradient (object coordinates)."""

    def phi(self, r: Any) -> float:
        """Surface function of Eq. 3 [m]."""
        ...

    def grad_phi(self, r: Any) -> FloatArray:
        """Gradient of ``phi``, shape (3,)."""
        ...


def solve_support(
    surface: ImplicitSurface,
    r1: Any,
    *,
    mass: float,
    gravity: Any,
    h: float,
    r2_guess: Any,
    tol: float = 1e-10,
    max_iter: int = 50,
) -> SupportSolution:
    """Support point on a general surface for a push ``h``: Eqs. 9-10 solved numerically.

    Gauss-Newton with backtracking on the residual (all in metres)::

        F(r2) = [phi(r2);  (r2 - r1) x a*(r2) - (M r1 x g~) / h],

    with the Jacobian by central differences (the surfaces expose ``grad phi`` but not
    its derivative). Meant for offline use (planning a support line), not per step.

    Parameters
    ----------
    surface : ImplicitSurface
        Object with ``phi(r)`` and ``grad_phi(r)`` (e.g. any ``GraspSurface``).
    r1 : array_like, shape (3,)
        Leader-hand origin [m], object coordinates.
    mass, gravity, h : keyword-only
        As in :func:`support_point`.
    r2_guess : array_like, shape (3,), keyword-only
        Starting point [m].
    tol : float, keyword-only
        Convergence tolerance on ``|F|`` [m].
    max_iter : int, keyword-only
        Iteration limit.

    Raises
    ------
    InvalidInputError
        Bad input, or no equilibrium found near ``r2_guess`` (Eq. 9 may have no
        solution on a curved surface: it needs ``(M r1 x g~) . a*(r2) = 0``).
    """
    a1 = as_array(r1, "r1", (3,))
    m, hh = _mass(mass), _push(h)
    gt = gravity_tilde(gravity)
    c_over_h = m * np.cross(a1, gt) / hh

    def unit_normal(r: FloatArray) -> FloatArray:
        g = np.asarray(surface.grad_phi(r), dtype=np.float64)
        n = float(np.linalg.norm(g))
        if not n > 1e-12:
            raise InvalidInputError(f"grad phi vanishes at r = {r}: no surface normal")
        return g / n

    def residual(r: FloatArray) -> FloatArray:
        out = np.empty(4)
        out[0] = float(surface.phi(r))
        out[1:] = np.cross(r - a1, unit_normal(r)) - c_over_h
        return out

    r, norm = _gauss_newton(residual, as_array(r2_guess, "r2_guess", (3,)).copy(), tol,
                            max_iter)
    if not norm <= max(tol, 1e-8):
        raise InvalidInputError(
            f"no support equilibrium found near r2_guess (residual {norm:.3g} m): "
            "Eq. 9 needs (M r1 x g~) . a*(r2) = 0 at the contact"
        )
    return _solution(a1, r, hh, unit_normal(r), m, gt)


def _gauss_newton(residual: Callable[[FloatArray], FloatArray], r: FloatArray, tol: float,
                  max_iter: int) -> tuple[FloatArray, float]:
    """Return the point Gauss-Newton with backtracking reaches from ``r``, and ``|F|`` there.

    The Jacobian by central differences; a step is halved until ``|F|`` decreases (the
    search stops when no step of at least 1e-6 does).
    """
    F = residual(r)
    norm = float(np.linalg.norm(F))
    for _ in range(max_iter):
        if norm <= tol:
            break
        J = np.empty((4, 3))
        for i in range(3):
            step = 1e-7 * max(1.0, abs(r[i]))
            e = np.zeros(3)
            e[i] = step
            J[:, i] = (residual(r + e) - residual(r - e)) / (2.0 * step)
        dr = np.linalg.lstsq(J, -F, rcond=None)[0]
        t = 1.0
        while t > 1e-6:
            r_new = r + t * dr
            F_new = residual(r_new)
            n_new = float(np.linalg.norm(F_new))
            if n_new < norm:
                break
            t *= 0.5
        else:
            break
        r, F, norm = r_new, F_new, n_new
    return r, norm


def support_sliding_vector(
    surface: ImplicitSurface,
    r1: Any,
    *,
    mass: float,
    gravity: Any,
    h: float,
    r2_guess: Any,
    rel_step: float = 1e-4,
) -> FloatArray:
    """Return the unit tangent ``s*`` of the support locus at push ``h``, any surface.

    Central difference of :func:`solve_support` in ``u = 1/h``, oriented like the
    plane formula (``r2`` moves along ``+s*`` as ``h`` decreases). On a plane prefer
    :func:`support_line`, which is exact.
    """
    hh = _push(h)
    u = 1.0 / hh
    du = rel_step * u
    lo = solve_support(surface, r1, mass=mass, gravity=gravity, h=1.0 / (u - du), r2_guess=r2_guess)
    hi = solve_support(surface, r1, mass=mass, gravity=gravity, h=1.0 / (u + du), r2_guess=lo.r2)
    d = hi.r2 - lo.r2
    n = float(np.linalg.norm(d))
    if n < 1e-14:
        raise InvalidInputError("the support point does not move with h: no sliding vector")
    return d / n


__all__ = ["ImplicitSurface", "solve_support", "support_sliding_vector"]
