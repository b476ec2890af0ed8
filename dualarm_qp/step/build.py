"""Pure functions that build one :class:`~dualarm_qp.step.StepProblem` (Eqs. 25-40).

Derivation (world frame, see docs/derivation.md). With ``d = p_f - p_l`` the vector
from the leader's tool origin to the grasp point, and ``R_o = R_l R_H1`` the object
orientation, the closure (Eq. 15) differentiates to

    v_f = v_l + w_l x d + R_o s*(sigma) m                (position, Eq. 23)
    w_f = w_l (+ R_o kappa(sigma) m on a curved path)    (orientation, Eq. 22)

so ``J_f [qf_dot; m] = J_l ql_dot`` with

    J_f = [[Jp_f, -R_o s*], [Ja_f, -R_o kappa]]            (Eq. 26)
    J_l = [[Jp_l - [d]x Ja_l], [Ja_l]]                     (Eq. 27: L1 + L2 = -[d]x Ja_l)

The paper freezes the orientation (kappa = 0 in Eq. 26) and re-resolves it after the
step (Sec. 3.3); ``exact_orientation=True`` keeps the curvature term instead.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from .._validate import as_array
from ..errors import InvalidInputError
from ..se3 import pose_error
from ..task.scene import DualArmTask
from .problem import StepProblem

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class DualArmState:
    """Measured state of the pair at one instant.

    Attributes
    ----------
    t : float
        Path time [s] at which the desired object pose D(t) is read.
    q_l, q_f : ndarray, shape (n_l,), (n_f,)
        Leader and follower joints [rad].
    sigma : float
        Follower grasp coordinate along the sliding path [m].
    """

    t: float
    q_l: FloatArray
    q_f: FloatArray
    sigma: float


@dataclass(frozen=True)
class StepOptions:
    """Settings of the step problem.

    Parameters
    ----------
    dt : float
        Sampling interval ``Delta T`` [s] (Eqs. 30-36).
    joint_weights : ndarray, shape (n_f,)
        Diagonal of S for the follower joints (Eq. 37) [1/(rad/s)^2].
    grasp_weight : float
        ``s7``, the weight of the sliding speed in SI units [1/(m/s)^2].
    velocity_limits : bool
        Intersect the position boxes with the joint speed limits and the grasp speed
        limit (the paper's closing remark). Default True.
    grasp_speed_max : float
        Limit on ``|m|`` [m/s]; ``inf`` for none.
    correction_gain : float
        Gain ``K`` [1/s] of the closure-error feedback added to the right-hand side,
        ``b = J_l ql_dot + K e``; 0 disables it. ``1/dt`` removes the whole error in one
        step (to first order).
    recovery_fraction : float
        A variable that starts outside its range must move back at least at this
        fraction of its speed limit (or all the way in one step when unlimited).
    exact_orientation : bool
        Keep the curvature term of the grasp frame in J_f (see module docstring).
    """

    dt: float
    joint_weights: FloatArray
    grasp_weight: float
    velocity_limits: bool = True
    grasp_speed_max: float = float("inf")
    correction_gain: float = 0.0
    recovery_fraction: float = 0.5
    exact_orientation: bool = False

    def __post_init__(self) -> None:
        if not (np.isfinite(self.dt) and self.dt > 0):
            raise InvalidInputError(f"dt must be a positive number of seconds, got {self.dt}")
        w = as_array(np.atleast_1d(self.joint_weights), "joint_weights", (-1,))
        if (w <= 0).any() or not (np.isfinite(self.grasp_weight) and self.grasp_weight > 0):
            raise InvalidInputError("weights must be finite and strictly positive")
        object.__setattr__(self, "joint_weights", w)
        if not self.grasp_speed_max > 0:
            raise InvalidInputError("grasp_speed_max must be positive")
        if not (np.isfinite(self.correction_gain) and self.correction_gain >= 0):
            raise InvalidInputError("correction_gain must be a finite number >= 0 [1/s]")
        if not 0 < self.recovery_fraction <= 1:
            raise InvalidInputError("recovery_fraction must be in (0, 1]")


@dataclass(frozen=True)
class StepBuild:
    """A built step: the problem and what the builder noticed on the way.

    Attributes
    ----------
    problem : StepProblem
        The problem handed to the solver.
    recovering : ndarray of bool, shape (n,)
        Variables that start outside their range (the box forces them back).
    closure_error : ndarray, shape (6,)
        ``[dp; dw]`` from the follower's tool to its target [m, rad].
    leader_rhs : ndarray, shape (6,)
        ``J_l ql_dot`` alone (without correction).
    """

    problem: StepProblem
    recovering: NDArray[np.bool_]
    closure_error: FloatArray
    leader_rhs: FloatArray = field(repr=False)


def rate_bounds(
    x: FloatArray,
    x_min: FloatArray,
    x_max: FloatArray,
    v_max: FloatArray,
    dt: float,
    recovery_fraction: float,
) -> tuple[FloatArray, FloatArray, FloatArray, NDArray[np.bool_]]:
    """Rate bounds from a position box and a speed limit (Eqs. 34-36 and Sec. 4).

    Parameters
    ----------
    x, x_min, x_max : ndarray
        Current positions and their box.
    v_max : ndarray
        Symmetric speed limits (``inf`` for none).
    dt : float
        Sampling interval [s].
    recovery_fraction : float
        See :class:`StepOptions`.

    Returns
    -------
    lower, upper : ndarray
        Hard bounds on the rate.
    center : ndarray
        Centre of the position-derived range (Eq. 39); 0 where the range is unbounded.
    recovering : ndarray of bool
        Positions outside their box.
    """
    lo = (x_min - x) / dt
    hi = (x_max - x) / dt
    with np.errstate(invalid="ignore"):
        center = np.where(np.isfinite(lo) & np.isfinite(hi), 0.5 * (lo + hi), 0.0)
    lower = np.maximum(lo, -v_max)
    upper = np.minimum(hi, v_max)
    below = lo > 0.0
    above = hi < 0.0
    recovering = below | above
    if recovering.any():
        rec = recovery_fraction * v_max
        lower = np.where(below, np.minimum(lo, rec), lower)
        upper = np.where(above, np.maximum(hi, -rec), upper)
    return lower, upper, center, recovering


def grasp_rate_range(
    surface_r: FloatArray,
    s_star: FloatArray,
    r_min: FloatArray,
    r_max: FloatArray,
    dt: float,
) -> tuple[float, float]:
    """``(rho_min, rho_max)`` of Eqs. 30-31 [m/s].

    Components with ``s*_i == 0`` do not move along axis i and are skipped.
    """
    rho_min, rho_max = -np.inf, np.inf
    for i in range(3):
        si = s_star[i]
        if abs(si) < 1e-12:
            continue
        a = (r_min[i] - surface_r[i]) / (si * dt)
        b = (r_max[i] - surface_r[i]) / (si * dt)
        rho_min = max(rho_min, min(a, b))
        rho_max = min(rho_max, max(a, b))
    return float(rho_min), float(rho_max)


def build_step(
    task: DualArmTask,
    state: DualArmState,
    ql_dot: FloatArray,
    options: StepOptions,
    *,
    leader_kin: tuple[FloatArray, FloatArray],
    follower_kin: tuple[FloatArray, FloatArray],
    x_prev: FloatArray | None = None,
) -> StepBuild:
    """Build the step problem of Eqs. 25-40 for the current state.

    Parameters
    ----------
    task : DualArmTask
        Arms, object, surface and path.
    state : DualArmState
        Current joints and grasp coordinate.
    ql_dot : ndarray, shape (n_l,)
        The leader's joint rates this step [rad/s].
    options : StepOptions
        Weights, limits and gains.
    leader_kin, follower_kin : tuple of ndarray
        ``(T, J)`` from ``arm.fk_jacobian`` at the current joints (computed by the
        caller so that kinematics is timed apart from assembly).
    x_prev : ndarray, optional
        Previous step's solution (warm start).

    Returns
    -------
    StepBuild
    """
    t_start = time.perf_counter()
    follower, surface = task.follower, task.surface
    n_f = follower.n
    if options.joint_weights.shape[0] not in (1, n_f):
        raise InvalidInputError(
            f"joint_weights has {options.joint_weights.shape[0]} entries, follower has {n_f}"
        )
    T_l, J_l = leader_kin
    T_f, J_fq = follower_kin
    sigma = state.sigma
    dt = options.dt

    R_o = T_l[:3, :3] @ task.H1[:3, :3]
    H2 = surface.pose(sigma)
    T_target = T_l @ task.H1 @ H2
    s_star = H2[:3, 0]
    d = T_target[:3, 3] - T_l[:3, 3]

    # Eq. 26: follower side, 6 x (n_f + 1).
    A = np.empty((6, n_f + 1))
    A[:, :n_f] = J_fq
    A[:3, n_f] = -(R_o @ s_star)
    A[3:, n_f] = -(R_o @ surface.angular_rate(sigma)) if options.exact_orientation else 0.0

    # Eq. 27: leader side, J_l ql_dot with L1 + L2 = -[d]x Ja_l.
    v_l = J_l[:3] @ ql_dot
    w_l = J_l[3:] @ ql_dot
    rhs = np.empty(6)
    rhs[:3] = v_l + np.array([w_l[1] * d[2] - w_l[2] * d[1],
                              w_l[2] * d[0] - w_l[0] * d[2],
                              w_l[0] * d[1] - w_l[1] * d[0]])
    rhs[3:] = w_l
    err = pose_error(T_target, T_f)
    b = rhs + options.correction_gain * err if options.correction_gain > 0 else rhs

    # Eqs. 34-36 and 39 for the joints.
    v_max = follower.qd_max if options.velocity_limits else np.full(n_f, np.inf)
    lo_q, hi_q, c_q, rec_q = rate_bounds(
        state.q_f, follower.q_min, follower.q_max, v_max, dt, options.recovery_fraction
    )
    # Eqs. 30-33 and 40 for the grasp, also kept inside the path's own range.
    r2 = H2[:3, 3]
    rho_min, rho_max = grasp_rate_range(r2, s_star, surface.r_min, surface.r_max, dt)
    rho_min = max(rho_min, (surface.sigma_min - sigma) / dt)
    rho_max = min(rho_max, (surface.sigma_max - sigma) / dt)
    m_max = options.grasp_speed_max if options.velocity_limits else np.inf
    lo_m, hi_m, c_m, rec_m = rate_bounds(
        np.zeros(1), np.array([rho_min]), np.array([rho_max]), np.array([m_max]), 1.0,
        options.recovery_fraction,
    )

    weights = np.empty(n_f + 1)
    weights[:n_f] = options.joint_weights
    weights[n_f] = options.grasp_weight
    problem = StepProblem(
        A=A,
        b=b,
        weights=weights,
        center=np.concatenate((c_q, c_m)),
        lower=np.concatenate((lo_q, lo_m)),
        upper=np.concatenate((hi_q, hi_m)),
        n_grasp=1,
        x_prev=x_prev,
        names=_names(n_f),
        build_time=time.perf_counter() - t_start,
    )
    return StepBuild(problem, np.concatenate((rec_q, rec_m)), err, rhs)


_NAME_CACHE: dict[int, tuple[str, ...]] = {}


def _names(n_f: int) -> tuple[str, ...]:
    names = _NAME_CACHE.get(n_f)
    if names is None:
        names = (*(f"qf{i + 1}" for i in range(n_f)), "m")
        _NAME_CACHE[n_f] = names
    return names
