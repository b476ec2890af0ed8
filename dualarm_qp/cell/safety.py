"""What keeps a cell safe whatever the solver says: the command clamp and the stop ramp.

Both work on the joint rates that are *sent* to the robots (both arms' joints, the
leader's first), sampled at the controller's ``dt``:

* **The clamp** (:meth:`CommandLimits.clamp`): every command is put inside the joints'
  speed limits and within ``qdd_max dt`` of the last command sent (acceleration), and,
  when the arm states ``qddd_max``, within ``qddd_max dt^2`` of the last command's
  extrapolation ``2 v[k-1] - v[k-2]`` (jerk). Speed and acceleration always hold; where
  the jerk box does not meet the speed and acceleration box (a command already braking
  as hard as it may, a speed limit reached at full acceleration), the command is the
  point of that box nearest to the jerk box: the jerk gives way no more than it must
  (where the boxes touch, as near a speed limit, rounding alone can part them).
* **The stop** (:class:`StopRamp`): both arms brought to rest together. Every joint's
  rate is the last command sent times one common factor ``s`` that falls from 1 to 0, so
  the arms keep moving along the direction they were moving in (the grasp closure, a
  linear condition on the rates, stays as it was) and no joint stops before another.
  ``s`` falls as fast as the joints' acceleration and jerk limits allow: each sample
  the largest decrease of ``s`` from which a jerk-limited landing at ``s = 0`` with no
  overshoot remains possible. Each ramp command then goes through the clamp too.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidInputError

if TYPE_CHECKING:
    from ..control.controller import DualArmController

FloatArray = NDArray[np.float64]

#: Longest stop, in samples, before :class:`StopRamp` gives up (a joint that cannot be
#: brought to rest in this many samples has a limit too small for its speed).
STOP_SAMPLES_MAX = 100_000


@dataclass(frozen=True)
class CommandLimits:
    """The limits every sent command keeps, per joint (both arms, the leader's first).

    Parameters
    ----------
    v_max : ndarray, shape (n,)
        Speed limits [rad/s] (``inf``: none).
    a_max : ndarray, shape (n,)
        Acceleration limits [rad/s^2] (``inf``: none).
    j_max : ndarray, shape (n,)
        Jerk limits [rad/s^3] (``inf``: none).
    dt : float
        The controller's sampling interval [s].
    """

    v_max: FloatArray
    a_max: FloatArray
    j_max: FloatArray
    dt: float

    def __post_init__(self) -> None:
        n = np.asarray(self.v_max).shape
        for name in ("v_max", "a_max", "j_max"):
            value = np.asarray(getattr(self, name), dtype=np.float64)
            if value.shape != n or not (value > 0).all():
                raise InvalidInputError(f"{name} must be {n[0] if n else 0} positive values "
                                        f"(inf: none), got {value}")
            object.__setattr__(self, name, value)
        if not (math.isfinite(self.dt) and self.dt > 0):
            raise InvalidInputError(f"dt must be a positive number of seconds, got {self.dt}")

    @property
    def n(self) -> int:
        """Number of joints."""
        return int(self.v_max.size)

    def box(self, v1: FloatArray, v2: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Return the rates a command after ``v1`` (and ``v2`` before it) may take [rad/s].

        Speed and acceleration always; the jerk box where it meets them, else the one
        rate of theirs nearest to it (see the module).
        """
        dt = self.dt
        lo = np.maximum(-self.v_max, v1 - self.a_max * dt)
        hi = np.minimum(self.v_max, v1 + self.a_max * dt)
        with np.errstate(invalid="ignore"):  # inf - inf where a joint has no limit
            centre = 2.0 * v1 - v2
            jlo = np.where(np.isfinite(self.j_max), centre - self.j_max * dt * dt, -np.inf)
            jhi = np.where(np.isfinite(self.j_max), centre + self.j_max * dt * dt, np.inf)
        lo_j, hi_j = np.maximum(lo, jlo), np.minimum(hi, jhi)
        meet = lo_j <= hi_j
        # Apart: the jerk box lies wholly above (jlo > hi) or below (jhi < lo) the other.
        near = np.where(jlo > hi, hi, lo)
        return np.where(meet, lo_j, near), np.where(meet, hi_j, near)

    def clamp(self, command: FloatArray, v1: FloatArray, v2: FloatArray) -> FloatArray:
        """Return ``command`` put inside :meth:`box` (``v1``: last sent, ``v2``: before)."""
        lo, hi = self.box(np.asarray(v1, dtype=np.float64), np.asarray(v2, dtype=np.float64))
        return np.minimum(np.maximum(np.asarray(command, dtype=np.float64), lo), hi)


def _ramp_out(d: float, J: float) -> float:
    """Change of ``s`` while its increment ``d < 0`` is brought back to 0 at ``J`` per sample.

    The increments after ``d`` are ``d + J, d + 2 J, ...``, the last one that is still
    negative included, then 0: their sum. With ``J`` infinite, one sample does it: 0.
    """
    if d >= 0.0 or math.isinf(J):
        return 0.0
    m = math.ceil(-d / J)  # samples until the increment reaches 0 (the m-th is 0)
    return (m - 1) * d + J * (m - 1) * m / 2.0


def command_limits(controller: DualArmController) -> CommandLimits:
    """Return the limits every sent command keeps: both arms' speeds, accelerations and jerks."""
    task = controller.task
    arms = (task.leader, task.follower)
    return CommandLimits(np.concatenate([a.qd_max for a in arms]),
                         np.concatenate([a.qdd_max for a in arms]),
                         np.concatenate([a.qddd_max for a in arms]), controller.options.dt)


def stop_samples_bound(lim: CommandLimits) -> int:
    """Return an upper bound of the stop ramp's samples from any speed within the limits."""
    dt = lim.dt
    bound = 2.0
    for v, a, j in zip(lim.v_max, lim.a_max, lim.j_max, strict=True):
        if math.isfinite(v) and math.isfinite(a):
            bound = max(bound, v / (a * dt) + (a / (j * dt) if math.isfinite(j) else 0.0))
    return int(min(math.ceil(2.0 * bound) + 4, STOP_SAMPLES_MAX))


class StopRamp:
    """Bring every joint to rest along the last command's direction (see the module).

    Parameters
    ----------
    limits : CommandLimits
        The joints' limits.
    v1 : ndarray, shape (n,)
        The last command sent [rad/s].
    v2 : ndarray, shape (n,)
        The command before it [rad/s].
    """

    def __init__(self, limits: CommandLimits, v1: FloatArray, v2: FloatArray) -> None:
        self.limits = limits
        self.direction = np.asarray(v1, dtype=np.float64).copy()
        self._last = (self.direction.copy(), np.asarray(v2, dtype=np.float64).copy())
        moving = np.abs(self.direction) > 0.0
        dt = limits.dt
        with np.errstate(divide="ignore"):
            speed = np.abs(self.direction[moving])
            self._A = float(np.min(limits.a_max[moving] * dt / speed, initial=np.inf))
            self._J = float(np.min(limits.j_max[moving] * dt * dt / speed, initial=np.inf))
        d0 = self.direction - self._last[1]
        norm2 = float(self.direction @ self.direction)
        self._s = 1.0 if norm2 > 0.0 else 0.0
        self._ds = float(self.direction @ d0) / norm2 if norm2 > 0.0 else 0.0
        self.samples = 0

    @property
    def at_rest(self) -> bool:
        """Whether the last command given was zero for every joint."""
        return not np.any(self._last[0])

    def _next_scale(self) -> float:
        """Return the next factor ``s``: the largest fall a landing at 0 still allows."""
        s, ds, A, J = self._s, self._ds, self._A, self._J
        if math.isinf(A) and math.isinf(J):
            return 0.0
        lo = max(ds - J, -A) if math.isfinite(J) else -A
        hi = min(ds + J, A) if math.isfinite(J) else A
        lo, hi = min(lo, hi), max(lo, hi)
        if s + lo + _ramp_out(lo, J) >= 0.0:
            return s + lo
        if s + hi + _ramp_out(hi, J) < 0.0:
            return max(s + hi, 0.0)
        a, b = lo, hi  # s + d + ramp_out(d) grows with d: the smallest d keeping it >= 0
        for _ in range(80):
            mid = 0.5 * (a + b)
            if s + mid + _ramp_out(mid, J) >= 0.0:
                b = mid
            else:
                a = mid
        return max(s + b, 0.0)

    def next(self) -> FloatArray:
        """Return the next command of the stop [rad/s] (zero for every joint once at rest).

        Raises
        ------
        InvalidInputError
            The joints cannot be brought to rest within :data:`STOP_SAMPLES_MAX` samples.
        """
        if self.samples >= STOP_SAMPLES_MAX:
            raise InvalidInputError(f"the stop did not bring the joints to rest within "
                                    f"{STOP_SAMPLES_MAX} samples")
        s = self._next_scale() if self._s > 0.0 else 0.0
        if s <= 1e-12:
            s = 0.0
        self._ds, self._s = s - self._s, s
        v1, v2 = self._last
        command = self.limits.clamp(s * self.direction, v1, v2)
        self._last = (command, v1)
        self.samples += 1
        return command


__all__ = ["STOP_SAMPLES_MAX", "CommandLimits", "StopRamp", "command_limits", "stop_samples_bound"]
