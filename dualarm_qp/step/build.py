"""Build the one step problem of both arms and every sliding grasp (Eqs. 14, 25-40).

The decision vector holds the leader's joint rates, the follower's joint rates and
the sliding speed of every sliding grasp, in this order:

    x = [ql_dot (n_l), qf_dot (n_f), m (follower grasp), m_l (leader grasp, if it slides)]

with two blocks of six equality rows (world frame, ``[v; w]``), both read from the
carried-object model (:class:`~dualarm_qp.task.carry.CarryModel`, where every sliding
grasp is a joint):

    J_o [ql_dot; m_l] = s V_o(t) + K_l e_l                       (Eq. 14 differentiated)
    J_f qf_dot - J_t [ql_dot; m; m_l] = K e_c                    (Eqs. 25-27)

``J_o`` is the Jacobian of the object frame (the leader's task: the object follows
``D(t)``, with path twist ``V_o`` and the feedback of its pose error ``e_l``); ``J_t`` is
the Jacobian of the follower's target frame ``T_l H1 H2(sigma)`` and ``J_f`` the
follower's tool Jacobian; ``e_c`` is the grasp closure error. With a rigid leader grasp
and a six-joint leader the first block fixes ``ql_dot`` and the second is the paper's
6x7 follower problem ``[J_f, -R_o s*] [qf_dot; m] = J_l' ql_dot + K e`` (Eqs. 25-27):
the columns of ``J_t`` over ``ql`` are ``[[Jp_l - [d]x Ja_l], [Ja_l]]`` (Eq. 27) and its
sliding column is ``[R_o s*; R_o kappa]`` (Eq. 26). The paper freezes the orientation
(kappa = 0 in Eq. 26) and re-resolves it after the step (Sec. 3.3);
``exact_orientation=True`` keeps the curvature term of the follower's grasp instead.

Every variable has a box from its range and its speed limit (Eqs. 30-36) and a centre
(Eqs. 38-40), weighted per variable (Eq. 37). ``s`` is the task scale of the
infeasible-step policy (:func:`~dualarm_qp.solvers.solve_step`), which multiplies the
whole right-hand side.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from .._validate import as_array
from ..errors import InvalidInputError, NonFiniteError, SupportLostError
from ..se3 import pose_error
from ..task.carry import CarryKinematics, CarryModel
from ..task.contact import SupportContact
from ..task.scene import DualArmTask
from ..task.support import SupportLine
from .bounds import clip_rates, grasp_rate_range
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
        Follower grasp coordinate along its sliding path [m].
    sigma_leader : float
        Leader grasp coordinate along its sliding path [m]; ignored (0) when the leader
        grasps rigidly.
    """

    t: float
    q_l: FloatArray
    q_f: FloatArray
    sigma: float
    sigma_leader: float = 0.0

    def advanced(self, command: Command, dt: float) -> DualArmState:
        """Return the state after applying ``command`` for ``dt`` seconds (explicit Euler).

        Joints move by ``dt`` times their rates, each grasp by ``dt`` times its sliding
        speed, and the path time by ``dt`` times the command's ``scale`` (the path slows
        when the task was scaled). ``command`` is a controller step's output
        (:class:`~dualarm_qp.control.controller.ControlOutput`) or anything with the
        same rates.
        """
        return DualArmState(self.t + dt * command.scale, self.q_l + dt * command.ql_dot,
                            self.q_f + dt * command.qf_dot, self.sigma + dt * command.m,
                            self.sigma_leader + dt * command.m_leader)


class Command(Protocol):
    """The rates one controller step commands (what :meth:`DualArmState.advanced` reads).

    Attributes
    ----------
    ql_dot, qf_dot : ndarray
        Joint rates of the leader and the follower [rad/s].
    m, m_leader : float
        Sliding speeds of the follower's and the leader's grasp [m/s].
    scale : float
        Path-time rate of the step (1: full speed).
    """

    @property
    def ql_dot(self) -> FloatArray:
        """Leader joint rates [rad/s]."""

    @property
    def qf_dot(self) -> FloatArray:
        """Follower joint rates [rad/s]."""

    @property
    def m(self) -> float:
        """Follower grasp sliding speed [m/s]."""

    @property
    def m_leader(self) -> float:
        """Leader grasp sliding speed [m/s]."""

    @property
    def scale(self) -> float:
        """Path-time rate of the step."""


@dataclass(frozen=True)
class StepOptions:
    """Settings of the step problem.

    Parameters
    ----------
    dt : float
        Sampling interval ``Delta T`` [s] (Eqs. 30-36).
    joint_weights : ndarray, shape (n_f,) or (1,)
        Diagonal of S for the follower joints (Eq. 37) [1/(rad/s)^2].
    grasp_weight : float
        ``s7``, the weight of every sliding speed in SI units [1/(m/s)^2].
    velocity_limits : bool
        Intersect the position boxes with the joint speed limits and the grasp speed
        limit (the paper's closing remark). Default True.
    grasp_speed_max : float
        Limit on every ``|m|`` [m/s]; ``inf`` for none.
    correction_gain : float, optional
        Gain ``K`` [1/s] of the closure-error feedback, ``b = ... + K e``; 0 disables it.
        Default ``1/dt``, which removes the whole error in one step (to first order).
    centre_horizon : float, optional
        Time [s] in which the range centres of Eqs. 39-40 ask each variable to reach the
        middle of its range: the centre rate is ``(middle - x) / centre_horizon``.
        Default ``dt``, the paper's choice. A longer horizon makes the centring gentler.
    recovery_fraction : float
        A variable that starts outside its range may never move further out; its
        centre (Eq. 39/40) pulls it back. With ``recovery_fraction > 0`` it must also
        move back at least at this fraction of its speed limit. Default 0: a forced
        return rate can make a step infeasible.
    exact_orientation : bool
        Keep the curvature term of the follower's grasp frame (see module docstring).
    leader_joint_weights : ndarray, shape (n_l,) or (1,), optional
        Diagonal of S for the leader joints [1/(rad/s)^2]; default 1. It matters only
        when the leader has more joints than the six rows of its task.
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
    leader_joint_weights: FloatArray | None = None

    def __post_init__(self) -> None:
        if not (np.isfinite(self.dt) and self.dt > 0):
            raise InvalidInputError(f"dt must be a positive number of seconds, got {self.dt}")
        w = as_array(np.atleast_1d(self.joint_weights), "joint_weights", (-1,))
        lw = as_array(np.atleast_1d(1.0 if self.leader_joint_weights is None
                                    else self.leader_joint_weights),
                      "leader_joint_weights", (-1,))
        if ((w <= 0).any() or (lw <= 0).any()
                or not (np.isfinite(self.grasp_weight) and self.grasp_weight > 0)):
            raise InvalidInputError("weights must be finite and strictly positive")
        object.__setattr__(self, "joint_weights", w)
        object.__setattr__(self, "leader_joint_weights", lw)
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
    """A built step: the problem and every quantity computed on the way.

    Attributes
    ----------
    problem : StepProblem
        The problem handed to the solver (rows: leader task, then closure).
    recovering : ndarray of bool, shape (n,)
        Variables that start outside their range (the box forces them back).
    closure_error : ndarray, shape (6,)
        ``[dp; dw]`` from the follower's tool to its target [m, rad].
    leader_error : ndarray, shape (6,)
        ``[dp; dw]`` from the object frame to ``D(t)`` [m, rad].
    carry : CarryKinematics
        Leader, object and target poses and Jacobians at this state.
    T_f, J_f : ndarray
        Follower tool pose (4, 4) and Jacobian (6, n_f).
    sigma_min : tuple of float
        Smallest singular value of the leader's and the follower's tool Jacobian.
    kinematics_time, assembly_time : float
        Seconds spent in the kinematics and in assembling the problem.
    support_force : float
        Follower push ``h`` [N] of a Case 2 support at this state (NaN for a grasp).
    """

    problem: StepProblem
    recovering: NDArray[np.bool_]
    closure_error: FloatArray
    leader_error: FloatArray
    carry: CarryKinematics
    T_f: FloatArray
    J_f: FloatArray
    sigma_min: tuple[float, float]
    kinematics_time: float
    assembly_time: float
    support_force: float = math.nan


def smallest_singular_value(J: FloatArray) -> float:
    """Smallest singular value of the joint Jacobian ``J`` (0 with fewer columns than rows)."""
    m, n = J.shape
    if n < m or n == 0:
        return 0.0
    return float(np.linalg.svd(J, compute_uv=False)[-1])


class StepBuilder:
    """Builds the step problems of one task under fixed options.

    What does not change from step to step (variable names, weights, limits, the
    carried-object model) is prepared once here; :meth:`build` does the per-step work:
    both arms' kinematics (once), the problem, the errors the trace records.

    Parameters
    ----------
    task : DualArmTask
        Arms, object, surfaces and path.
    options : StepOptions
        Weights, limits and gains.
    leader_gain : float, optional
        Feedback gain ``K_l`` [1/s] of the object's tracking of ``D(t)``; default ``1/dt``.
    leader_bounds : bool
        Impose the leader's joint ranges and speed limits (hard-limit solvers); False
        leaves its box open (the paper's methods, which ignore limits by design).

    Raises
    ------
    InvalidInputError
        A weight vector of the wrong length.
    """

    def __init__(self, task: DualArmTask, options: StepOptions, *,
                 leader_gain: float | None = None, leader_bounds: bool = True) -> None:
        leader, follower, surface = task.leader, task.follower, task.surface
        n_l, n_f = leader.n, follower.n
        for w, n, who in ((options.joint_weights, n_f, "joint_weights (follower)"),
                          (options.leader_joint_weights, n_l, "leader_joint_weights")):
            if w is not None and w.shape[0] not in (1, n):
                raise InvalidInputError(f"{who} has {w.shape[0]} entries, the arm has {n}")
        self.task = task
        self.options = options
        self.carry = CarryModel(leader, surface, task.H1, task.leader_surface)
        k = self.carry.n_grasp
        self.n_l, self.n_f, self.n_grasp = n_l, n_f, k
        self.n = n_l + n_f + k
        self.names: tuple[str, ...] = (*(f"ql{i + 1}" for i in range(n_l)),
                                       *(f"qf{i + 1}" for i in range(n_f)),
                                       "m", *(("m_l",) if k == 2 else ()))
        weights = np.empty(self.n)
        weights[:n_l] = options.leader_joint_weights if options.leader_joint_weights is not None \
            else 1.0
        weights[n_l:n_l + n_f] = options.joint_weights
        weights[n_l + n_f:] = options.grasp_weight
        weights.flags.writeable = False  # shared by every problem this builder makes
        self.weights = weights
        inf = math.inf
        limits = options.velocity_limits
        m_max = options.grasp_speed_max if limits else inf
        self._x_min = np.r_[leader.q_min if leader_bounds else np.full(n_l, -inf),
                            follower.q_min]
        self._x_max = np.r_[leader.q_max if leader_bounds else np.full(n_l, inf),
                            follower.q_max]
        self._v_max = np.r_[leader.qd_max if leader_bounds and limits else np.full(n_l, inf),
                            follower.qd_max if limits else np.full(n_f, inf),
                            np.full(k, m_max)]
        self.leader_gain = 1.0 / options.dt if leader_gain is None else leader_gain
        self._surfaces = [surface] + ([] if task.leader_surface is None
                                      else [task.leader_surface])
        self._contact = task.contact

    @property
    def speed_limits(self) -> FloatArray:
        """Speed limit of every decision variable [rad/s, m/s] (``inf``: none)."""
        return self._v_max

    def build(self, state: DualArmState, *, scale_max: float = 1.0,
              x_prev: FloatArray | None = None) -> StepBuild:
        """Build the step problem for ``state``.

        Parameters
        ----------
        state : DualArmState
            Joints [rad], grasp coordinates [m] and path time [s] (checked by the caller).
        scale_max : float
            Share in [0, 1] of the path's feed-forward twist (1: full speed).
        x_prev : ndarray, optional
            Previous step's solution (warm start).

        Raises
        ------
        NonFiniteError
            The problem would hold NaN or infinity.
        InvalidInputError
            A supporting follower (Case 2) would have to pull at this state.
        """
        t0 = time.perf_counter()
        task, opts = self.task, self.options
        n_l, n_f, n = self.n_l, self.n_f, self.n
        sigma, sigma_l = state.sigma, state.sigma_leader
        kin = self.carry.update(state.q_l, sigma, sigma_l)
        support_force = math.nan
        if self._contact is not None:
            kin, support_force = self._support(self._contact, kin, state)
        T_f, J_f = task.follower.fk_jacobian(state.q_f)
        sigma_min = (smallest_singular_value(kin.J_tool), smallest_singular_value(J_f))
        t1 = time.perf_counter()

        dt = opts.dt
        traj = task.trajectory
        e_l = pose_error(traj.pose(state.t), kin.T_object)
        e_c = pose_error(kin.T_target, T_f)
        A = np.zeros((12, n))
        b = np.empty(12)
        grasps = slice(n_l + n_f, n)
        # Leader task: the object frame follows D(t).
        A[:6, :n_l] = kin.J_object[:, :n_l]
        A[:6, grasps] = kin.J_object[:, n_l:]
        b[:6] = scale_max * traj.twist(state.t) + self.leader_gain * e_l
        # Closure: the follower's tool moves with its target.
        A[6:, :n_l] = -kin.J_target[:, :n_l]
        A[6:, n_l:n_l + n_f] = J_f
        A[6:, grasps] = -kin.J_target[:, n_l:]
        if not opts.exact_orientation:
            A[9:, n_l + n_f] = 0.0  # the paper's frozen orientation of the follower's grasp
        b[6:] = float(opts.correction_gain or 0.0) * e_c
        if not (np.isfinite(A).all() and np.isfinite(b).all()):
            raise NonFiniteError("the step's equality (D(t), its twist or the arms' poses)")

        # Eqs. 34-36 for the joints; Eqs. 30-33 for the grasps, also kept inside their
        # paths' own ranges; Eqs. 39-40 for the centres.
        lo = np.empty(n)
        hi = np.empty(n)
        q = np.concatenate((state.q_l, state.q_f))  # finite: no inf - inf below
        lo[:n_l + n_f] = (self._x_min - q) / dt
        hi[:n_l + n_f] = (self._x_max - q) / dt
        for i, (surf, s) in enumerate(zip(self._surfaces, (sigma, sigma_l)[:self.n_grasp],
                                          strict=True)):
            r2 = surf.point(s)
            rho_min, rho_max = grasp_rate_range(r2, surf.tangent(s), surf.r_min, surf.r_max, dt)
            lo[n_l + n_f + i] = max(rho_min, (surf.sigma_min - s) / dt)
            hi[n_l + n_f + i] = min(rho_max, (surf.sigma_max - s) / dt)
        lower, upper, center, recovering = clip_rates(lo, hi, self._v_max,
                                                      opts.recovery_fraction)
        horizon = opts.centre_horizon or dt
        if horizon != dt:  # the centre rates were computed for dt
            center = center * (dt / horizon)
        problem = StepProblem(A, b, self.weights, center, lower, upper,
                              n_grasp=self.n_grasp, names=self.names, x_prev=x_prev)
        t2 = time.perf_counter()
        return StepBuild(problem, recovering, e_c, e_l, kin, T_f, J_f, sigma_min,
                         t1 - t0, t2 - t1, support_force)

    def _support(self, contact: SupportContact, kin: CarryKinematics, state: DualArmState
                 ) -> tuple[CarryKinematics, float]:
        """Case 2: put the follower's path on the support line of this step; its push.

        The line is computed for the object's orientation at ``state`` and frozen for
        the step (as the paper freezes the grasp frame, Sec. 3.3). When it moved, the
        follower's grasp joint is re-placed and the kinematics recomputed; the target
        then jumps by the line's motion at ``sigma``, which the closure feedback
        removes. The grasp bounds of the step are the line's (``h > 0``).

        Raises
        ------
        InvalidInputError
            No pushing support for this orientation, the line reversed (gravity's
            component along the push changed sign), or ``h <= 0`` at ``sigma``.
        """
        line = contact.line(kin.T_object[:3, :3])
        current = self._surfaces[0]
        if (isinstance(current, SupportLine)
                and float(line.tangent(0.0) @ current.tangent(0.0)) < 0.0):
            raise SupportLostError(
                "support lost: the support line reversed (gravity's component along the "
                "surface normal changed sign), so the follower would have to pull")
        if not np.allclose(line.pose(0.0), current.pose(0.0), rtol=0.0, atol=1e-12):
            self.carry.place_follower(line)
            kin = self.carry.update(state.q_l, state.sigma, state.sigma_leader)
        self._surfaces[0] = line
        return kin, contact.force(line, state.sigma)
