"""Leave an exact singularity: a bounded move that raises an arm's smallest singular value.

At a singular configuration an arm's Jacobian loses rank. When the path asks for the
lost direction, no rate meets the step's equality at any positive task scale: the scale
policy slows the path to zero, and the state never changes, because nothing in the
step asks the arm to leave the singularity. A UR10 whose wrist starts at ``q5 = 0``
stalls there for good.

When the task scale has collapsed this way (below :data:`COLLAPSED_SCALE`, with an arm's
smallest singular value below the threshold), the controller takes an **escape move**
instead of standing still (status ESCAPING, path time held):

1. the gradient of the arm's smallest singular value ``sigma`` in its joints,
   ``d sigma / d q_j = u^T (d J / d q_j) v`` (``u``, ``v`` its singular vectors; the
   Jacobian's derivative by central differences);
2. projected on the null space of the step's equality rows, so that the object and
   the grasp closure hold to first order; when that projection has less than
   :data:`NULL_SHARE` of the gradient (no self-motion of the pair raises ``sigma``),
   the gradient itself, with its first-order error on the equality capped at
   :data:`ERROR_SHARE` of the error budget per step (the feedback removes it);
3. added to the step's own answer at task scale 0 (which meets every bound and every
   row), as far as every bound allows and no further than needed to lift ``sigma`` to
   twice the threshold within one sample.

At an exact singularity ``sigma = |f(q)|`` is not differentiable; its singular vectors
give the gradient of ``f`` up to a sign, and both signs raise ``sigma``: the move takes
the sign its bounds allow further.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..kinematics.arm import SerialArm
from ..solvers._affine import factor
from ..step.problem import StepProblem

FloatArray = NDArray[np.float64]

#: A step whose task scale is below this has collapsed (the path all but stops).
COLLAPSED_SCALE = 1e-3

#: Share of the gradient a null-space projection must keep to be used alone.
NULL_SHARE = 0.1

#: Share of the error budget that one escape move off the null space may cost.
ERROR_SHARE = 0.25

#: A smallest singular value at or below this is an exact zero (rounding level): both
#: signs of its gradient raise it.
EXACT_ZERO = 1e-12

#: Central-difference step for the Jacobian's derivative [rad].
JACOBIAN_STEP = 1e-6


@dataclass(frozen=True)
class Escape:
    """An escape move.

    Attributes
    ----------
    x : ndarray
        The rates to apply [rad/s, m/s].
    arms : tuple of str
        The arms it lifts (``"leader"``, ``"follower"``).
    null_space : bool
        Whether the move keeps the step's equality to first order.
    rate : float
        Predicted rate of increase of the smallest singular value [1/s].
    """

    x: FloatArray
    arms: tuple[str, ...]
    null_space: bool
    rate: float


def sigma_gradient(arm: SerialArm, q: FloatArray) -> tuple[float, FloatArray]:
    """Smallest singular value of the arm's tool Jacobian and its gradient in ``q``.

    Parameters
    ----------
    arm : SerialArm
        The arm.
    q : ndarray, shape (n,)
        Joints [rad].

    Returns
    -------
    sigma : float
        The smallest singular value (0 with fewer joints than six).
    gradient : ndarray, shape (n,)
        ``d sigma / d q`` (at an exact zero: the gradient of the signed value, up to
        sign).
    """
    J = arm.jacobian(q)
    m, n = J.shape
    U, sv, Vt = np.linalg.svd(J)
    k = min(m, n) - 1
    u, v = U[:, k], Vt[k]
    grad = np.empty(n)
    h = JACOBIAN_STEP
    for j in range(n):
        dq = np.zeros(n)
        dq[j] = h
        dJ = (arm.jacobian(q + dq) - arm.jacobian(q - dq)) / (2.0 * h)
        grad[j] = float(u @ dJ @ v)
    return float(sv[k]), grad


def escape_move(problem: StepProblem, base: FloatArray,
                arms: tuple[tuple[str, SerialArm, slice, FloatArray], ...], threshold: float,
                dt: float, budget: float) -> Escape | None:
    """Return the escape move from ``base``, or None when no bound lets it move.

    Parameters
    ----------
    problem : StepProblem
        The step (its equality rows and its box).
    base : ndarray
        The step's collapsed answer [rad/s, m/s]: within the box, ``A x = s b`` with
        the task scale ``s`` below :data:`COLLAPSED_SCALE`.
    arms : tuple
        ``(role, arm, slice of the decision vector, joints)`` of every arm below the
        threshold.
    threshold : float
        The singular value to lift the arms above (the move aims at twice it).
    dt : float
        Sampling interval [s].
    budget : float
        Position error budget [m]: a move off the null space costs at most
        :data:`ERROR_SHARE` of it per step.
    """
    g = np.zeros(problem.n)
    deficit = 0.0
    exact = True
    for _role, arm, cols, q in arms:
        sigma, grad = sigma_gradient(arm, q)
        g[cols] += grad
        deficit = max(deficit, 2.0 * threshold - sigma)
        exact = exact and sigma <= EXACT_ZERO
    if not float(np.abs(g).max(initial=0.0)) > 0.0:
        return None
    # At an exact zero both signs of the gradient raise sigma: try the other one when
    # the bounds stop the first.
    for sign in ((1.0, -1.0) if exact else (1.0,)):
        d, on_null = _direction(problem, base, sign * g)
        rate = float(sign * g @ d)  # d sigma / d alpha
        if not rate > 0.0:
            continue
        _, hi_a = _interval(base, d, problem.lower, problem.upper)
        alpha = min(deficit / (dt * rate), hi_a)
        if not on_null:  # the equality moves by dt |A d| alpha: keep it in its share
            drift = dt * float(np.abs(problem.A @ d).max(initial=0.0))
            if drift > 0.0:
                alpha = min(alpha, ERROR_SHARE * budget / drift)
        if alpha > 0.0:
            x = np.clip(base + alpha * d, problem.lower, problem.upper)
            return Escape(x, tuple(a[0] for a in arms), on_null, alpha * rate)
    return None


def _direction(problem: StepProblem, base: FloatArray, g: FloatArray
               ) -> tuple[FloatArray, bool]:
    """Project the gradient ``g`` on what the bounds and the equality leave free.

    A variable at a bound that ``g`` would push past it is held (its component 0) and the
    projection on the null space of the free columns is taken again, until no held
    variable is pushed out (at most ``n`` rounds). When that null-space projection
    keeps less than :data:`NULL_SHARE` of ``g``, the free part of ``g`` itself is used.

    Returns
    -------
    d : ndarray
        The direction (0 on the held variables).
    on_null : bool
        Whether ``d`` lies in the null space of the equality.
    """
    n = problem.n
    span = np.maximum(1.0, np.abs(base))
    at_lo = base <= problem.lower + 1e-12 * span
    at_up = base >= problem.upper - 1e-12 * span
    g_size = float(np.linalg.norm(g))
    for on_null in (True, False):
        free = np.ones(n, dtype=bool)
        for _ in range(n):
            d = np.zeros(n)
            if on_null:
                N = factor(problem.A[:, free]).N
                d[free] = N @ (N.T @ g[free])
            else:
                d[free] = g[free]
            pushed = (at_lo & (d < 0.0)) | (at_up & (d > 0.0))
            if not pushed.any():
                break
            free &= ~pushed
        if float(np.linalg.norm(d)) >= NULL_SHARE * g_size or not on_null:
            return d, on_null
    return d, False


def _interval(base: FloatArray, d: FloatArray, lower: FloatArray, upper: FloatArray
              ) -> tuple[float, float]:
    """``[a_lo, a_hi]``: the steps ``alpha`` with ``base + alpha d`` in the box."""
    a_lo, a_hi = -np.inf, np.inf
    moving = np.abs(d) > 1e-12 * float(np.abs(d).max())
    with np.errstate(divide="ignore", invalid="ignore"):
        to_lo = (lower - base)[moving] / d[moving]
        to_hi = (upper - base)[moving] / d[moving]
    ends = np.sort(np.stack([to_lo, to_hi]), axis=0)
    if ends.size:
        a_lo = float(ends[0].max())
        a_hi = float(ends[1].min())
    return min(a_lo, 0.0), max(a_hi, 0.0)


__all__ = ["COLLAPSED_SCALE", "Escape", "escape_move", "sigma_gradient"]
