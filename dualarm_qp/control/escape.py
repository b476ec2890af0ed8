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
   :data:`ERROR_SHARE` of the error budget per step (the feedback removes it); a box or
   row already active that the direction would push past is held (projected out);
3. added to the step's own answer at its collapsed scale (which meets every box and
   row), as far as every box and row allows and no further than needed to lift
   ``sigma`` to twice the threshold within one sample.

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
        alpha = min(deficit / (dt * rate), _reach(problem, base, d))
        if not on_null:  # the equality moves by dt |A d| alpha: keep it in its share
            drift = dt * float(np.abs(problem.A @ d).max(initial=0.0))
            if drift > 0.0:
                alpha = min(alpha, ERROR_SHARE * budget / drift)
        if alpha > 0.0:
            x = np.clip(base + alpha * d, problem.lower, problem.upper)  # rounding only
            return Escape(x, tuple(a[0] for a in arms), on_null, alpha * rate)
    return None


def _direction(problem: StepProblem, base: FloatArray, g: FloatArray
               ) -> tuple[FloatArray, bool]:
    """Project the gradient ``g`` on what the limits and the equality leave free.

    Every box and general row active at ``base`` (within rounding) that ``g`` would push
    past is held: the projection is taken again on the null space of the held rows (and
    of the equality), until no held row is pushed out (at most one round per row). When
    that null-space projection keeps less than :data:`NULL_SHARE` of ``g``, the
    projection on the held rows alone (off the equality's null space) is used.

    Returns
    -------
    d : ndarray
        The direction.
    on_null : bool
        Whether ``d`` lies in the null space of the equality.
    """
    ineq = problem.inequalities()
    C, e = ineq.C, ineq.e
    active = C @ base >= e - 1e-12 * np.maximum(1.0, np.abs(e))
    g_size = float(np.linalg.norm(g))
    d = g
    for on_null in (True, False):
        held = np.zeros(C.shape[0], dtype=bool)
        for _ in range(C.shape[0] + 1):
            rows = [problem.A] if on_null else []
            rows.append(C[held])
            N = factor(np.vstack(rows)).N
            d = N @ (N.T @ g)
            pushed = active & ~held & (C @ d > 1e-12 * float(np.linalg.norm(d)))
            if not pushed.any():
                break
            held |= pushed
        if not on_null or float(np.linalg.norm(d)) >= NULL_SHARE * g_size:
            return d, on_null
    return d, False


def _reach(problem: StepProblem, base: FloatArray, d: FloatArray) -> float:
    """Return the largest ``alpha >= 0`` with ``base + alpha d`` inside every box and row."""
    ineq = problem.inequalities()
    rate = ineq.C @ d
    slack = ineq.e - ineq.C @ base
    moving = rate > 1e-15 * max(1.0, float(np.abs(d).max(initial=0.0)))
    if not moving.any():
        return np.inf
    return max(float((np.maximum(slack[moving], 0.0) / rate[moving]).min()), 0.0)


__all__ = ["COLLAPSED_SCALE", "Escape", "escape_move", "sigma_gradient"]
