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
iterations suffice. The iterations run in the compiled kernel (``kernel.ik_dls``), on
the arm's own kinematic chain: per iteration one small LU solve with partial pivoting,
one forward kinematics and one pose error (the Jacobian is recomputed only when another
iteration follows). This function checks the input and reports.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._compiled import kernel
from ..errors import IKError, InvalidInputError
from .arm import FloatArray, SerialArm, checked_pose

#: Bounds on the adaptive damping factor ``mu`` (see the module docstring).
_MU_MIN, _MU_MAX = 1e-12, 1e16

#: Largest iteration budget handed to the kernel (a 64-bit count; never reached).
_ITERATIONS_CAP = 2**62

#: The kernel's reasons to stop (``kernel.ik_dls``'s last answer), for the error message.
_CONVERGED = 0
_STOPS = ("converged", "maximum number of iterations reached",
          "stalled (local minimum of the error: target out of reach or blocked by joint "
          "limits)", "stalled (no step lowers the error)")


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
    q = arm.check_q(q0, "q0").copy()
    lo = arm.q_min if respect_limits else np.full(arm.n, -math.inf)
    hi = arm.q_max if respect_limits else np.full(arm.n, math.inf)
    answer = kernel.ik_dls(
        arm.chain, arm.tool_frame_id, target, q, lo, hi, float(tol_pos), float(tol_rot),
        min(max_iter, _ITERATIONS_CAP), float(damping), _MU_MIN, _MU_MAX)
    iterations, ep, er = answer.iterations, answer.position_error, answer.rotation_error
    success = answer.stop == _CONVERGED
    result = IKResult(q, success, iterations, ep, er)
    if not success and raise_on_failure:
        raise IKError(
            f"{arm.name}: ik_dls did not converge after {iterations} iterations "
            f"({_STOPS[answer.stop]}); best position error {ep:.3g} m, rotation error {er:.3g} rad",
            position_error=ep,
            rotation_error=er,
        )
    return result

