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

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from .._validate import as_array
from ..errors import InvalidInputError, NonFiniteError, ShapeError
from ..se3 import compose_rows, pose_error_rows
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
    correction_gain : float, optional
        Gain ``K`` [1/s] of the closure-error feedback added to the right-hand side,
        ``b = J_l ql_dot + K e``; 0 disables it. Default ``1/dt``, which removes the
        whole error in one step (to first order).
    centre_horizon : float, optional
        Time [s] in which the range centres of Eqs. 39-40 ask each variable to reach the
        middle of its range: the centre rate is ``(middle - x) / centre_horizon``.
        Default ``dt``, the paper's choice; the centring pull per step then does not
        shrink with ``dt``. A longer horizon makes the centring gentler.
    recovery_fraction : float
        A variable that starts outside its range may never move further out; its
        centre (Eq. 39/40) pulls it back. With ``recovery_fraction > 0`` it must also
        move back at least at this fraction of its speed limit (or all the way in one
        step when unlimited). Default 0: a forced return rate can make a step
        infeasible (the box then excludes every motion the equality allows).
    exact_orientation : bool
        Keep the curvature term of the grasp frame in J_f (see module docstring).
    """

    dt: float
    joint_weights: FloatArray
    grasp_weight: float
    velocity_limits: bool = True
    grasp_speed_max: float = float("inf")
    correction_gain: float | None = None
    recovery_fraction: float = 0.0
    exact_orientation: bool = False
    centre_horizon: float | None = None

    def __post_init__(self) -> None:
        if not (np.isfinite(self.dt) and self.dt > 0):
            raise InvalidInputError(f"dt must be a positive number of seconds, got {self.dt}")
        w = as_array(np.atleast_1d(self.joint_weights), "joint_weights", (-1,))
        if (w <= 0).any() or not (np.isfinite(self.grasp_weight) and self.grasp_weight > 0):
            raise InvalidInputError("weights must be finite and strictly positive")
        object.__setattr__(self, "joint_weights", w)
        if not self.grasp_speed_max > 0:
            raise InvalidInputError("grasp_speed_max must be positive")
        if self.correction_gain is None:
            object.__setattr__(self, "correction_gain", 1.0 / self.dt)
        elif not (np.isfinite(self.correction_gain) and self.correction_gain >= 0):
            raise InvalidInputError("correction_gain must be a finite number >= 0 [1/s]")
        if self.centre_horizon is None:
            object.__setattr__(self, "centre_horizon", self.dt)
        elif not (np.isfinite(self.centre_horizon) and self.centre_horizon > 0):
            raise InvalidInputError("centre_horizon must be a positive number of seconds")
        if not 0 <= self.recovery_fraction <= 1:
            raise InvalidInputError("recovery_fraction must be in [0, 1]")


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
    lo = np.asarray((np.asarray(x_min) - x) / dt, dtype=np.float64)
    hi = np.asarray((np.asarray(x_max) - x) / dt, dtype=np.float64)
    v = np.broadcast_to(np.asarray(v_max, dtype=np.float64), lo.shape)
    lower, upper, center, recovering = _clip_rates(
        lo.ravel().tolist(), hi.ravel().tolist(), v.ravel().tolist(), recovery_fraction
    )
    shape = lo.shape
    return (np.array(lower).reshape(shape), np.array(upper).reshape(shape),
            np.array(center).reshape(shape), np.array(recovering, dtype=bool).reshape(shape))


def _clip_rates(
    lo: list[float], hi: list[float], v_max: list[float], recovery_fraction: float
) -> tuple[list[float], list[float], list[float], list[bool]]:
    """:func:`rate_bounds` from the position-derived rate range ``[lo, hi]``.

    Python floats: for a handful of variables numpy's per-call cost exceeds the work.
    """
    lower, upper, center, recovering = [], [], [], []
    inf = math.inf
    for lo_i, hi_i, v_i in zip(lo, hi, v_max, strict=True):
        center.append(0.5 * (lo_i + hi_i) if -inf < lo_i < inf and -inf < hi_i < inf else 0.0)
        # Below the box: may not move further down; with a recovery fraction it must
        # move up at least at that share of its speed limit. Above the box: mirrored.
        rec = recovery_fraction * v_i if recovery_fraction > 0.0 else 0.0
        if lo_i > 0.0:
            lower.append(min(lo_i, rec))
        else:
            lower.append(max(lo_i, -v_i))
        if hi_i < 0.0:
            upper.append(max(hi_i, -rec))
        else:
            upper.append(min(hi_i, v_i))
        recovering.append(lo_i > 0.0 or hi_i < 0.0)
    return lower, upper, center, recovering


def grasp_rate_range(
    surface_r: Sequence[float] | FloatArray,
    s_star: Sequence[float] | FloatArray,
    r_min: Sequence[float] | FloatArray,
    r_max: Sequence[float] | FloatArray,
    dt: float,
) -> tuple[float, float]:
    """``(rho_min, rho_max)`` of Eqs. 30-31 [m/s].

    Components with ``s*_i == 0`` do not move along axis i and are skipped. The
    arguments are 3-vectors (arrays or lists of floats).
    """
    rho_min, rho_max = -math.inf, math.inf
    for i in range(3):
        si = float(s_star[i])
        if abs(si) < 1e-12:
            continue
        a = (float(r_min[i]) - float(surface_r[i])) / (si * dt)
        b = (float(r_max[i]) - float(surface_r[i])) / (si * dt)
        rho_min = max(rho_min, min(a, b))
        rho_max = min(rho_max, max(a, b))
    return rho_min, rho_max


class StepBuilder:
    """Builds the step problems of one task under fixed options (Eqs. 25-40).

    What does not change from step to step (variable names, the weights, the
    follower's limits, the surface's box) is prepared once here; :meth:`build` then
    does only the per-step work, in Python floats where numpy's per-call cost would
    dominate. The builder reads ``task`` and ``options`` when it is created: make a
    new one if either changes. :func:`build_step` is the one-off form.

    Parameters
    ----------
    task : DualArmTask
        Arms, object, surface and path.
    options : StepOptions
        Weights, limits and gains.

    Raises
    ------
    InvalidInputError
        ``options.joint_weights`` has neither 1 nor ``task.follower.n`` entries.
    """

    def __init__(self, task: DualArmTask, options: StepOptions) -> None:
        follower, surface = task.follower, task.surface
        n_f = follower.n
        if options.joint_weights.shape[0] not in (1, n_f):
            raise InvalidInputError(
                f"joint_weights has {options.joint_weights.shape[0]} entries, follower has {n_f}"
            )
        self.task = task
        self.options = options
        self.n = n_f + 1
        self.names: tuple[str, ...] = (*(f"qf{i + 1}" for i in range(n_f)), "m")
        weights = np.empty(n_f + 1)
        weights[:n_f] = options.joint_weights
        weights[n_f] = options.grasp_weight
        weights.flags.writeable = False  # shared by every problem this builder makes
        self.weights = weights
        # The object frame is often the leader's tool frame: skip composing with I.
        self._H1 = None if np.array_equal(task.H1, np.eye(4)) else task.H1.tolist()
        self._q_min = follower.q_min.tolist()
        self._q_max = follower.q_max.tolist()
        v_max = follower.qd_max.tolist() if options.velocity_limits else [math.inf] * n_f
        m_max = options.grasp_speed_max if options.velocity_limits else math.inf
        self._v_max = [*v_max, m_max]
        self._r_min = surface.r_min.tolist()
        self._r_max = surface.r_max.tolist()

    def build(
        self,
        state: DualArmState,
        ql_dot: FloatArray,
        *,
        leader_kin: tuple[FloatArray, FloatArray],
        follower_kin: tuple[FloatArray, FloatArray],
        x_prev: FloatArray | None = None,
    ) -> StepBuild:
        """Build the step problem for the current state; see :func:`build_step`."""
        t_start = time.perf_counter()
        task, options = self.task, self.options
        surface = task.surface
        n_f = self.n - 1
        T_l, J_l = leader_kin
        T_f, J_fq = follower_kin
        sigma = state.sigma
        dt = options.dt

        # Follower target T_l H1 H2(sigma) (Eq. 15), as rows of Python floats.
        # H2 = surface.pose(sigma), from its parts: cheaper than the 4x4 array.
        R2 = surface.frame(sigma).tolist()
        r2 = surface.point(sigma).tolist()
        H2 = [[*R2[0], r2[0]], [*R2[1], r2[1]], [*R2[2], r2[2]]]
        l_rows = T_l.tolist()
        object_rows = l_rows if self._H1 is None else compose_rows(l_rows, self._H1)
        target = compose_rows(object_rows, H2)
        # R_o s* is the target's x axis (R_o = R_l R_H1, s* = R_H2 e_x).
        column = [-target[0][0], -target[1][0], -target[2][0]]
        if options.exact_orientation:
            R_o = T_l[:3, :3] @ task.H1[:3, :3]
            column += (-(R_o @ surface.angular_rate(sigma))).tolist()
        else:
            column += (0.0, 0.0, 0.0)
        if not math.isfinite(sum(column)):
            raise NonFiniteError("A")
        # Eq. 27: leader side, J_l ql_dot with L1 + L2 = -[d]x Ja_l, d = p_target - p_l.
        v0, v1, v2, w0, w1, w2 = (J_l @ ql_dot).tolist()
        d0 = target[0][3] - l_rows[0][3]
        d1 = target[1][3] - l_rows[1][3]
        d2 = target[2][3] - l_rows[2][3]
        rhs = [v0 + (w1 * d2 - w2 * d1), v1 + (w2 * d0 - w0 * d2), v2 + (w0 * d1 - w1 * d0),
               w0, w1, w2]
        err = pose_error_rows(target, T_f.tolist())
        gain = float(options.correction_gain or 0.0)
        b = [r + gain * e for r, e in zip(rhs, err, strict=True)] if gain > 0 else rhs
        if not math.isfinite(sum(b)):
            raise NonFiniteError("b")

        # Eqs. 34-36 for the joints; Eqs. 30-33 for the grasp, also kept inside the
        # path's own range; Eqs. 39-40 for the centre.
        q = state.q_f.tolist()
        lo = [(lo_i - q_i) / dt for lo_i, q_i in zip(self._q_min, q, strict=True)]
        hi = [(hi_i - q_i) / dt for hi_i, q_i in zip(self._q_max, q, strict=True)]
        s_star = (R2[0][0], R2[1][0], R2[2][0])
        rho_min, rho_max = grasp_rate_range(r2, s_star, self._r_min, self._r_max, dt)
        lo.append(max(rho_min, (surface.sigma_min - sigma) / dt))
        hi.append(min(rho_max, (surface.sigma_max - sigma) / dt))
        lower, upper, center, recovering = _clip_rates(
            lo, hi, self._v_max, options.recovery_fraction
        )
        horizon = options.centre_horizon or dt
        if horizon != dt:  # the centre rates were computed for dt
            ratio = dt / horizon
            center = [c * ratio for c in center]

        A = np.empty((6, n_f + 1))
        A[:, :n_f] = J_fq
        A[:, n_f] = column
        # One conversion for every float output, then views of it.
        n = self.n
        values = np.array(b + center + lower + upper + err + rhs)
        problem = StepProblem.trusted(
            A, values[:6], self.weights, values[6:6 + n], values[6 + n:6 + 2 * n],
            values[6 + 2 * n:6 + 3 * n],
            names=self.names, x_prev=_checked_x_prev(x_prev, n),
            build_time=time.perf_counter() - t_start,
        )
        e0 = 6 + 3 * n
        return StepBuild(problem, np.array(recovering), values[e0:e0 + 6], values[e0 + 6:])


def _checked_x_prev(x_prev: FloatArray | None, n: int) -> FloatArray | None:
    """``x_prev`` as a float (n,) array, as :class:`StepProblem` would check it."""
    if x_prev is None or (isinstance(x_prev, np.ndarray) and x_prev.dtype == np.float64
                          and x_prev.shape == (n,)):
        return x_prev
    xp = np.asarray(x_prev, dtype=np.float64)
    if xp.shape != (n,):
        raise ShapeError("x_prev", (n,), xp.shape)
    return xp


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

    One-off form of :class:`StepBuilder` (a controller keeps a builder instead).

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

    Raises
    ------
    NonFiniteError
        The problem would hold NaN or infinity (e.g. a non-finite ``ql_dot``).
    """
    return StepBuilder(task, options).build(
        state, ql_dot, leader_kin=leader_kin, follower_kin=follower_kin, x_prev=x_prev
    )
