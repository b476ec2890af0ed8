"""The settings of the step problem: sampling interval, weights, limits and gains."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .._validate import as_array
from ..errors import InvalidInputError

FloatArray = NDArray[np.float64]


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
    leader_gain : float, optional
        Gain ``K_l`` [1/s] of the feedback of the object's pose error to ``D(t)``;
        default ``1/dt`` likewise. (The one place where the ``1/dt`` defaults are set.)
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
    acceleration_limits : bool
        Keep every joint's acceleration within its arm's ``qdd_max`` and every grasp's
        within ``grasp_acc_max``, with a braking bound so that a stop inside the range
        stays possible (:mod:`dualarm_qp.step.limits.acceleration`). Default False.
    grasp_acc_max : float
        Limit on every grasp's sliding acceleration [m/s^2]; ``inf`` for none.
    torque_limits : bool
        Keep every joint's quasi-static torque (its arm's weight and its hand's share
        of the load) within its limit, linearised over the sample
        (:mod:`dualarm_qp.step.limits.torque`). Default False.
    leader_tau_max, follower_tau_max : ndarray, shape (n,), optional
        Joint torque limits [N m] (``inf``: none); default the arm's model's ``effort``
        (a URDF's), which a DH arm does not have.
    torque_approach : float, optional
        Time constant [s] with which a joint's torque may approach its limit: each
        sample closes at most ``dt / torque_approach`` of the margin (None: all of it,
        in one sample).
    jerk_limits : bool
        Keep every joint's jerk within its arm's ``qddd_max`` and every grasp's within
        ``grasp_jerk_max``: each rate within ``j dt^2`` of the last two commands'
        extrapolation (:mod:`dualarm_qp.step.limits.jerk`). Default False.
    grasp_jerk_max : float
        Limit on every grasp's sliding jerk [m/s^3]; ``inf`` for none.
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
    acceleration_limits: bool = False
    grasp_acc_max: float = float("inf")
    leader_gain: float | None = None
    torque_limits: bool = False
    leader_tau_max: FloatArray | None = None
    follower_tau_max: FloatArray | None = None
    torque_approach: float | None = None
    jerk_limits: bool = False
    grasp_jerk_max: float = float("inf")

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
        if not self.grasp_acc_max > 0:
            raise InvalidInputError("grasp_acc_max must be positive")
        if self.torque_approach is not None and not (np.isfinite(self.torque_approach)
                                                     and self.torque_approach > 0):
            raise InvalidInputError("torque_approach must be a positive number of seconds, "
                                    f"got {self.torque_approach}")
        if not self.grasp_jerk_max > 0:
            raise InvalidInputError("grasp_jerk_max must be positive")
        for name in ("correction_gain", "leader_gain"):
            gain = getattr(self, name)
            if gain is None:
                object.__setattr__(self, name, 1.0 / self.dt)
            elif not (np.isfinite(gain) and gain >= 0):
                raise InvalidInputError(f"{name} must be a finite number >= 0 [1/s]")
        if self.centre_horizon is None:
            object.__setattr__(self, "centre_horizon", self.dt)
        elif not (np.isfinite(self.centre_horizon) and self.centre_horizon > 0):
            raise InvalidInputError("centre_horizon must be a positive number of seconds")
        if not 0 <= self.recovery_fraction <= 1:
            raise InvalidInputError("recovery_fraction must be in [0, 1]")


__all__ = ["StepOptions"]
