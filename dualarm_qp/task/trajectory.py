"""Desired object trajectories ``D(t)`` with exact twists (paper Eq. 14 and Section 4).

A trajectory gives the pose ``T_world_object(t)`` (4x4) of the object frame in the
world frame (for the paper: the leader's base frame, "the 0th coordinate frame of the
leader") and its exact time derivatives, never by differencing:

* ``twist(t) = [v; w]``: velocity of the object origin [m/s] and angular velocity
  [rad/s], both in world coordinates;
* ``acceleration(t) = [dv/dt; dw/dt]`` [m/s^2; rad/s^2], world coordinates.

Outside ``[t0, tf]`` the pose is clamped to ``D(t0)`` / ``D(tf)`` and the twist and the
acceleration are zero. On the closed interval the derivatives are the one-sided limits
from inside (so a :class:`LinearTrajectory` has its full velocity at ``t = tf``).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._compiled import kernel
from .._validate import as_array, as_number, as_pose
from ..errors import InvalidInputError, NonFiniteError, ShapeError

FloatArray = NDArray[np.float64]

__all__ = [
    "Trajectory",
    "LinearTrajectory",
    "WaypointTrajectory",
    "paper_trajectory",
    "min_jerk",
    "PAPER_R0",
    "PAPER_P0",
    "PAPER_VELOCITY",
]

#: Orientation of D(t) in the paper (Section 4): object x along world z, y along x, z along y.
PAPER_R0 = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])
#: Position of D(0) [m]: [-0.3, 690, 260.4] mm.
PAPER_P0 = np.array([-0.3e-3, 0.690, 0.2604])
#: Velocity of D(t) [m/s]: d_x(t) = t/31 - 0.3 with t in ms and d_x in mm, 1 mm per 31 ms.
PAPER_VELOCITY = np.array([1.0 / 31.0, 0.0, 0.0])
#: Shortest time between two waypoints [s] (a rest-to-rest segment shorter than this has
#: no meaningful rates: its acceleration would overflow).
MIN_SEGMENT = 1e-9

for _a in (PAPER_R0, PAPER_P0, PAPER_VELOCITY):
    _a.setflags(write=False)


def min_jerk(tau: float) -> tuple[float, float, float]:
    """Quintic minimum-jerk time scaling and its derivatives in ``tau`` (dimensionless).

    ``s = 10 tau^3 - 15 tau^4 + 6 tau^5`` on ``[0, 1]``: ``s(0) = 0``, ``s(1) = 1`` and
    zero first and second derivatives at both ends. Returns ``(s, ds/dtau, d2s/dtau2)``,
    for a number or elementwise for an array. A :class:`WaypointTrajectory` evaluates the
    same polynomials, in the same order, in the kernel.
    """
    t2 = tau * tau
    s = t2 * tau * (10.0 + tau * (-15.0 + 6.0 * tau))
    ds = t2 * (30.0 + tau * (-60.0 + 30.0 * tau))
    dds = tau * (60.0 + tau * (-180.0 + 120.0 * tau))
    return s, ds, dds


class Trajectory(ABC):
    """Desired object pose ``D(t)`` in the world frame with its exact derivatives.

    Attributes
    ----------
    t0, tf : float
        Start and end time [s], ``t0 < tf``.
    """

    t0: float
    tf: float

    @property
    def duration(self) -> float:
        """``tf - t0`` [s]."""
        return self.tf - self.t0

    @abstractmethod
    def pose(self, t: float) -> FloatArray:
        """``T_world_object(t)``, shape (4, 4); clamped outside ``[t0, tf]``."""

    @abstractmethod
    def twist(self, t: float) -> FloatArray:
        """``[v; w]`` at ``t`` [m/s; rad/s], world frame, velocity of the object origin.

        Zero outside ``[t0, tf]``.
        """

    @abstractmethod
    def acceleration(self, t: float) -> FloatArray:
        """``[dv/dt; dw/dt]`` at ``t`` [m/s^2; rad/s^2], world frame; zero outside."""


class LinearTrajectory(Trajectory):
    """Constant orientation, constant velocity: ``p(t) = p0 + v (t - t0)``.

    Parameters
    ----------
    p0 : array_like, shape (3,)
        Position of the object origin at ``t0`` [m], world frame.
    velocity : array_like, shape (3,)
        Constant velocity [m/s], world frame.
    R0 : array_like, shape (3, 3), keyword-only
        Constant orientation ``R_world_object`` (a proper rotation); identity by default.
    t0 : float, keyword-only
        Start time [s].
    tf : float, keyword-only
        End time [s], ``> t0``.

    Notes
    -----
    ``pose`` and ``twist`` avoid numpy arithmetic (a few microseconds per call); they
    return fresh arrays the caller may modify.
    """

    def __init__(
        self,
        p0: Any,
        velocity: Any,
        *,
        R0: Any = None,
        t0: float = 0.0,
        tf: float,
    ) -> None:
        p = as_array(p0, "p0", (3,))
        v = as_array(velocity, "velocity", (3,))
        R = np.eye(3) if R0 is None else as_array(R0, "R0", (3, 3))
        T0 = as_pose(_pose_from(R, p), "R0")
        self.t0 = as_number(t0, "t0")
        self.tf = as_number(tf, "tf")
        if not self.tf > self.t0:
            raise InvalidInputError(f"tf ({self.tf:g} s) must be greater than t0 ({self.t0:g} s)")
        self._T0 = T0
        self._p0 = (float(p[0]), float(p[1]), float(p[2]))
        self._v = (float(v[0]), float(v[1]), float(v[2]))
        self._twist = np.zeros(6)
        self._twist[:3] = v

    @property
    def p0(self) -> FloatArray:
        """Position at ``t0`` [m]."""
        return np.array(self._p0)

    @property
    def velocity(self) -> FloatArray:
        """Constant velocity [m/s]."""
        return np.array(self._v)

    @property
    def R0(self) -> FloatArray:
        """Constant orientation ``R_world_object``."""
        return self._T0[:3, :3].copy()

    def pose(self, t: float) -> FloatArray:
        """``[R0, p0 + v (clip(t) - t0); 0 0 0 1]``."""
        dt = min(max(t, self.t0), self.tf) - self.t0
        if dt != dt:
            raise NonFiniteError("t")
        T = self._T0.copy()
        p, v = self._p0, self._v
        T[0, 3] = p[0] + v[0] * dt
        T[1, 3] = p[1] + v[1] * dt
        T[2, 3] = p[2] + v[2] * dt
        return T

    def twist(self, t: float) -> FloatArray:
        """``[v; 0]`` on ``[t0, tf]``, zero outside."""
        if t != t:
            raise NonFiniteError("t")
        if self.t0 <= t <= self.tf:
            return self._twist.copy()
        return np.zeros(6)

    def acceleration(self, t: float) -> FloatArray:
        """Zero."""
        return np.zeros(6)


def paper_trajectory(*, duration: float, t0: float = 0.0) -> LinearTrajectory:
    """Build the paper's ``D(t)`` (Section 4) in SI units.

    ``R = [[0, 1, 0], [0, 0, 1], [1, 0, 0]]``, ``p(t) = [t/31 - 0.3, 690, 260.4]`` mm with
    ``t`` in ms, i.e. ``p0 = [-0.3e-3, 0.690, 0.2604]`` m and ``v = [1/31, 0, 0]`` m/s,
    expressed in the leader's base frame. The paper does not state the duration, so it
    must be given.

    Parameters
    ----------
    duration : float, keyword-only
        ``tf - t0`` [s], > 0.
    t0 : float, keyword-only
        Start time [s] (``D(t0)`` has ``d_x = -0.3`` mm).
    """
    start = as_number(t0, "t0")
    return LinearTrajectory(
        PAPER_P0, PAPER_VELOCITY, R0=PAPER_R0, t0=start, tf=start + as_number(duration, "duration")
    )


def _pose_from(R: FloatArray, p: FloatArray) -> FloatArray:
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = p
    return T


class WaypointTrajectory(Trajectory):
    """Rest-to-rest motion through SE(3) waypoints with minimum-jerk timing.

    On segment ``k`` (``t_k <= t <= t_{k+1}``), with ``tau = (t - t_k) / (t_{k+1} - t_k)``
    and the quintic :func:`min_jerk` scaling ``s(tau)``:

    * ``p(t) = p_k + s (p_{k+1} - p_k)`` (straight line in position),
    * ``R(t) = R_k exp(s w_k)`` with ``w_k = log(R_k^T R_{k+1})`` (geodesic in rotation),

    so ``v = s_dot (p_{k+1} - p_k)`` and ``w_world = s_dot R_k w_k`` exactly (``exp(s w_k)``
    fixes ``w_k``), and likewise for the accelerations with ``s_ddot``. The object stops
    (zero velocity and acceleration) at every waypoint; position and rotation follow the
    same timing, so the path is a screw-free "straight line plus geodesic" per segment.
    When consecutive orientations differ by exactly pi rad the geodesic is not unique;
    ``pinocchio.log3`` then picks one of the two.

    Parameters
    ----------
    times : array_like, shape (N,)
        Waypoint times [s], N >= 2, finite and strictly increasing.
    poses : array_like, shape (N, 4, 4)
        Waypoints ``T_world_object`` (proper rotations, last row [0, 0, 0, 1]).

    Raises
    ------
    ShapeError
        Wrong shapes or mismatched counts.
    NonFiniteError
        NaN or infinity in the input.
    InvalidInputError
        Fewer than two waypoints, times not strictly increasing, or an improper rotation.
    """

    def __init__(self, times: Any, poses: Any) -> None:
        ts = as_array(times, "times", (-1,))
        if ts.size < 2:
            raise InvalidInputError(f"need at least two waypoints, got {ts.size}")
        if np.any(np.diff(ts) <= 0.0):
            k = int(np.flatnonzero(np.diff(ts) <= 0.0)[0])
            raise InvalidInputError(
                f"times must be strictly increasing: times[{k}] = {ts[k]:g} s, "
                f"times[{k + 1}] = {ts[k + 1]:g} s"
            )
        if np.any(np.diff(ts) < MIN_SEGMENT):
            k = int(np.flatnonzero(np.diff(ts) < MIN_SEGMENT)[0])
            raise InvalidInputError(
                f"waypoints must be at least {MIN_SEGMENT:g} s apart: times[{k}] = "
                f"{ts[k]:.17g} s, times[{k + 1}] = {ts[k + 1]:.17g} s"
            )
        try:
            Ps = np.asarray(poses, dtype=np.float64)
        except (TypeError, ValueError, OverflowError) as err:
            raise InvalidInputError(f"poses must be an (N, 4, 4) array: {err}") from err
        if Ps.shape != (ts.size, 4, 4):
            raise ShapeError("poses", (ts.size, 4, 4), Ps.shape)
        Ts = [as_pose(Ps[i], f"poses[{i}]").copy() for i in range(ts.size)]
        self._times = [float(x) for x in ts]
        self.t0 = self._times[0]
        self.tf = self._times[-1]
        self._poses = Ts
        # Every evaluation runs in the kernel, with one fixed order of every sum (the
        # kernel's path pickles itself).
        self._path = kernel.WaypointPath(self._times, np.concatenate(Ts))

    @property
    def times(self) -> FloatArray:
        """Waypoint times [s]."""
        return np.array(self._times)

    @property
    def waypoints(self) -> list[FloatArray]:
        """Copies of the waypoint poses."""
        return [T.copy() for T in self._poses]

    def pose(self, t: float) -> FloatArray:
        """``T_world_object(t)``, clamped to the first / last waypoint outside."""
        T = np.empty((4, 4))
        self._path.pose(as_number(t, "t"), T)
        return T

    def twist(self, t: float) -> FloatArray:
        """``[s_dot dp; s_dot R_k w_k]`` [m/s; rad/s]; zero outside ``[t0, tf]``."""
        return self._derivative(t, 1)

    def acceleration(self, t: float) -> FloatArray:
        """``[s_ddot dp; s_ddot R_k w_k]`` [m/s^2; rad/s^2]; zero outside ``[t0, tf]``."""
        return self._derivative(t, 2)

    def _derivative(self, t: float, order: int) -> FloatArray:
        """Return the ``order``-th time derivative (1 or 2) of the pose as a 6-vector."""
        out = np.empty(6)
        self._path.derivative(as_number(t, "t"), order, out)
        return out
