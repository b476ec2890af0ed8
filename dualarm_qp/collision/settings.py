"""The settings of collision avoidance: the velocity damper's distances, in SI units.

For each pair closer than the influence distance ``d_i`` the step asks

    d_dot >= -xi (d - d_s) / (d_i - d_s)

of the pair's distance ``d`` (the velocity damper of Faverjon and Tournassoud, 1987):
far pairs give no row, a pair may approach at ``xi`` at most where it enters the band,
and the rate allowed falls linearly to zero at the safety distance ``d_s``. Below
``d_s`` the right-hand side is positive: the pair must separate.

To first order one step of ``dt`` then cannot cross ``d_s``: from
``d_dot >= -xi (d - d_s) / (d_i - d_s)``, ``d + d_dot dt - d_s >= (d - d_s)(1 - xi dt /
(d_i - d_s))``, which stays non-negative when ``xi dt <= d_i - d_s``
(:meth:`CollisionSettings.check_dt`). What remains is the second-order term of the
step, ``d_ddot dt^2 / 2``, for which a recorded clearance may fall below ``d_s`` by
:data:`CLEARANCE_ALLOWANCE` at most.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..errors import InvalidInputError

#: How far [m] a recorded clearance may fall below the safety distance: the
#: second-order term of one step, ``d_ddot dt^2 / 2``. 1 mm covers a relative
#: acceleration of the witness points of 20 m/s^2 at dt = 10 ms. Measured: the shipped
#: collision configurations end 0.02 to 0.11 mm above ``d_s``; the deepest undershoot in
#: the tests is 0.001 mm (a pair held at ``d_s`` until the task is blocked).
CLEARANCE_ALLOWANCE = 1e-3


@dataclass(frozen=True)
class CollisionSettings:
    """The velocity damper's distances, in SI units.

    Parameters
    ----------
    enabled : bool
        Whether the step keeps the pairs apart (False: the clearance is only measured).
    influence_distance : float
        ``d_i`` [m]: a pair closer than this gives a row.
    safety_distance : float
        ``d_s`` [m]: the distance no pair may fall below.
    approach_speed_max : float
        ``xi`` [m/s]: the largest rate at which a pair at ``d_i`` may approach; the rate
        allowed falls linearly to 0 at ``d_s``.
    grasp_clearance : float
        [m] The links of a grasping hand this close to its grasp point at the start are
        not paired with the object (they touch it by design).
    """

    enabled: bool = True
    influence_distance: float = 0.1
    safety_distance: float = 0.02
    approach_speed_max: float = 0.2
    grasp_clearance: float = 0.15

    def __post_init__(self) -> None:
        if not (math.isfinite(self.safety_distance) and self.safety_distance >= 0):
            raise InvalidInputError("safety_distance must be a finite number >= 0 [m], got "
                                    f"{self.safety_distance!r}")
        if not (math.isfinite(self.influence_distance)
                and self.influence_distance > self.safety_distance):
            raise InvalidInputError("influence_distance must be finite and larger than "
                                    f"safety_distance [m], got {self.influence_distance!r}")
        if not (math.isfinite(self.approach_speed_max) and self.approach_speed_max > 0):
            raise InvalidInputError("approach_speed_max must be a positive number [m/s], got "
                                    f"{self.approach_speed_max!r}")
        if not (math.isfinite(self.grasp_clearance) and self.grasp_clearance >= 0):
            raise InvalidInputError("grasp_clearance must be a finite number >= 0 [m], got "
                                    f"{self.grasp_clearance!r}")

    @property
    def band(self) -> float:
        """``d_i - d_s`` [m]."""
        return self.influence_distance - self.safety_distance

    def allowed_rate(self, distance: float) -> float:
        """Return the smallest rate of change [m/s] allowed at the distance ``distance`` [m]."""
        return -self.approach_speed_max * (distance - self.safety_distance) / self.band

    def check_dt(self, dt: float) -> None:
        """Refuse a sampling interval over which one step could cross ``d_s`` to first order.

        Raises
        ------
        InvalidInputError
            ``approach_speed_max dt > influence_distance - safety_distance``.
        """
        if self.approach_speed_max * dt > self.band:
            raise InvalidInputError(
                f"approach_speed_max * dt = {self.approach_speed_max * dt:.4g} m exceeds "
                f"influence_distance - safety_distance = {self.band:.4g} m: one step could "
                "cross the safety distance; lower approach_speed_max or dt, or widen the band")

    def summary(self) -> dict[str, object]:
        """JSON-ready settings (SI)."""
        return {"enabled": self.enabled, "influence_distance_m": self.influence_distance,
                "safety_distance_m": self.safety_distance,
                "approach_speed_max_m_s": self.approach_speed_max,
                "grasp_clearance_m": self.grasp_clearance,
                "allowance_m": CLEARANCE_ALLOWANCE}


__all__ = ["CLEARANCE_ALLOWANCE", "CollisionSettings"]
