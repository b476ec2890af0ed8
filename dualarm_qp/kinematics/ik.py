"""Numerical inverse kinematics for any arm: damped least squares (Levenberg-Marquardt).

The residual is the world-frame pose error ``e = [p* - p; log(R* R^T)]`` ([m]; [rad])
and the model is the geometric Jacobian: ``e(q + dq) ~ e(q) - J dq``. Each iteration
solves

    (J_F^T J_F + lambda I) dq_F = J_F^T e,        lambda = mu |e|^2

over the free joints F (a joint resting on a limit whose step would push it further out
is frozen for that iteration), clips ``q + dq`` into the limits, and keeps the step only
if it lowers ``|e|``. Because ``lambda`` shrinks with ``|e|^2`` the method becomes
Gauss-Newton near a solution and converges quadratically (the approximation error of
``J`` for the rotation part is itself O(|e|)); far from a solution or near a singularity
the damping keeps steps short. ``mu`` adapts to the ratio ``rho`` of actual to
predicted decrease: x10 after a rejected step, x2 when ``rho < 0.25``, /3 when
``rho > 0.75``.

From a nearby guess (the per-step drift correction of a controller) one or two
iterations suffice: the call costs one :meth:`SerialArm.fk_jacobian`, then per
iteration one small linear solve, one :meth:`SerialArm.fk` and one pose error (the
Jacobian is recomputed only when another iteration follows).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import IKError, InvalidInputError
from ..se3 import pose_error_rows
from .arm import FloatArray, SerialArm, checked_pose

#: Bounds on the adaptive damping factor ``mu`` (see the module docstring).
_MU_MIN, _MU_MAX = 1e-12, 1e16


@dataclass(frozen=True)
class IKResult:
    """Outcome of :func:`ik_dls`.

    Attributes
    ----------
    q : ndarray, shape (n,)
        Best joint angles found [rad] (within the limits when they were respected).
    success : bool
        Whether both tolerances were met.
    iterations : int
        Linear solves performed (0 when ``q0`` already met the tolerances).
    position_error : float
        ``|p* - p(q)|`` [m].
    rotation_error : float
        Angle of ``R* R(q)^T`` [rad].
    """

    q: FloatArray
    success: bool
    iterations: int
    position_error: float
    rotation_error: float


def ik_dls(
    arm: SerialArm,
    T_target: Any,
    q0: Any,
    *,
    tol_pos: float = 1e-10,
    tol_rot: float = 1e-10,
    max_iter: int = 200,
    damping: float = 1e-2,
    respect_limits: bool = True,
    raise_on_failure: bool = True,
) -> IKResult:
    """Joint angles placing the tool at ``T_target``, by damped least squares.

    Parameters
    ----------
    arm : SerialArm
        Any arm (DH or URDF chain); its base and tool are taken into account.
    T_target : array_like, shape (4, 4)
        Desired ``T_world_tool`` [m].
    q0 : array_like, shape (n,)
        Initial guess [rad]. With ``respect_limits`` it is first clipped into the limits.
    tol_pos : float
        Position tolerance [m].
    tol_rot : float
        Rotation tolerance [rad].
    max_iter : int
        Maximum number of linear solves (iterations), >= 0.
    damping : float
        Initial damping factor ``mu`` > 0 [1/m^2, mixed units]: ``lambda = mu |e|^2``.
    respect_limits : bool
        Keep every iterate within ``[q_min, q_max]``.
    raise_on_failure : bool
        Raise :class:`~dualarm_qp.errors.IKError` instead of returning an unsuccessful
        result.

    Returns
    -------
    IKResult
        The last (and best) iterate with its errors.

    Raises
    ------
    IKError
        The tolerances were not met (``raise_on_failure=True``): the target is out of
        reach or blocked by the limits, or the iteration stalled in a local minimum.
        ``position_error`` and ``rotation_error`` hold the best errors reached.
    InvalidInputError
        Malformed arm, pose, ``q0`` or options.
    """
    if not isinstance(arm, SerialArm):
        raise InvalidInputError(f"arm must be a SerialArm, got {type(arm).__name__}")
    if not (tol_pos > 0.0 and tol_rot > 0.0):
        raise InvalidInputError(f"tolerances must be positive, got {tol_pos}, {tol_rot}")
    if not (damping > 0.0 and math.isfinite(damping)):
        raise InvalidInputError(f"damping must be positive and finite, got {damping}")
    if isinstance(max_iter, bool) or not isinstance(max_iter, int) or max_iter < 0:
        raise InvalidInputError(f"max_iter must be an int >= 0, got {max_iter!r}")
    target = checked_pose(T_target, "T_target")
    n = arm.n
    # Small per-joint logic runs on Python floats: numpy costs microseconds per call.
    lo = arm.q_min.tolist() if respect_limits else [-math.inf] * n
    hi = arm.q_max.tolist() if respect_limits else [math.inf] * n
    qs = [min(max(x, a), b)
          for x, a, b in zip(arm.check_q(q0, "q0").tolist(), lo, hi, strict=True)]
    q = np.array(qs)

    T, J = arm.fk_jacobian(q)
    e, ep, er = _pose_error(target, T)
    cost = ep * ep + er * er  # |e|^2
    mu = damping
    iterations = 0
    reason = "maximum number of iterations reached"
    while not (ep <= tol_pos and er <= tol_rot):
        if iterations >= max_iter:
            break
        iterations += 1
        g = J.T @ e  # steepest-descent direction of |e|^2 / 2
        gs = g.tolist()
        # Freeze joints that sit on a limit and would be pushed past it.
        free = [i for i in range(n) if not ((qs[i] <= lo[i] and gs[i] < 0.0)
                                            or (qs[i] >= hi[i] and gs[i] > 0.0))]
        if len(free) < n:
            Jf, gf = J[:, free], g[free]
        else:
            Jf, gf = J, g
        A = Jf.T @ Jf
        A.flat[:: len(free) + 1] += mu * cost
        try:
            dq_free = np.linalg.solve(A, gf).tolist()
        except np.linalg.LinAlgError:
            mu *= 10.0
            continue
        dq = [0.0] * n
        for i, d in zip(free, dq_free, strict=True):
            dq[i] = d
        q_new_s = [min(max(x + d, a), b) for x, d, a, b in zip(qs, dq, lo, hi, strict=True)]
        step_s = [x1 - x0 for x1, x0 in zip(q_new_s, qs, strict=True)]
        if max(map(abs, step_s)) <= 1e-15 * (1.0 + max(map(abs, qs))):
            reason = ("stalled (local minimum of the error: target out of reach or "
                      "blocked by joint limits)")
            break
        q_new = np.array(q_new_s)
        T_new = arm.fk(q_new)  # the Jacobian is only needed if the step is kept
        e_new, ep_new, er_new = _pose_error(target, T_new)
        cost_new = ep_new * ep_new + er_new * er_new
        if cost_new < cost:
            if not (ep_new <= tol_pos and er_new <= tol_rot):  # adapt mu for the next step
                Js = J @ np.array(step_s)
                predicted = 2.0 * float(e @ Js) - float(Js @ Js)  # model decrease of |e|^2
                rho = (cost - cost_new) / predicted if predicted > 0.0 else 0.0
                if rho > 0.75:
                    mu = max(mu / 3.0, _MU_MIN)
                elif rho < 0.25:
                    mu = min(mu * 2.0, _MU_MAX)
                J = arm.jacobian(q_new)
            q, qs, e, ep, er, cost = q_new, q_new_s, e_new, ep_new, er_new, cost_new
        else:
            mu *= 10.0
            if mu > _MU_MAX:
                reason = "stalled (no step lowers the error)"
                break

    success = ep <= tol_pos and er <= tol_rot
    result = IKResult(q, success, iterations, ep, er)
    if not success and raise_on_failure:
        raise IKError(
            f"{arm.name}: ik_dls did not converge after {iterations} iterations ({reason}); "
            f"best position error {ep:.3g} m, rotation error {er:.3g} rad",
            position_error=ep,
            rotation_error=er,
        )
    return result


def _pose_error(T_target: FloatArray, T: FloatArray) -> tuple[FloatArray, float, float]:
    """``e = [p* - p; log(R* R^T)]`` and the norms of its two halves ([m], [rad])."""
    e = pose_error_rows(T_target.tolist(), T.tolist())
    return (np.array(e), math.sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]),
            math.sqrt(e[3] * e[3] + e[4] * e[4] + e[5] * e[5]))
