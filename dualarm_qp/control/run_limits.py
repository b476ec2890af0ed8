"""What a run must keep to complete, and how far it may run (:class:`RunLimits`)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..errors import InvalidInputError

#: What a smallest singular value below the threshold does.
SINGULARITY_ACTIONS = ("warn", "stop", "ignore")


@dataclass(frozen=True)
class RunLimits:
    """What a run must keep to complete, and how far it may run.

    Parameters
    ----------
    closure : tuple of float
        ``(position [m], rotation [rad])`` of the grasp closure error (default 1 mm,
        0.01 rad): beyond it the object would be torn or dropped.
    tracking : tuple of float
        ``(position [m], rotation [rad])`` of the leader's error to ``D(path time)``
        (default 1 mm, 0.01 rad).
    singular_value_min : float
        Threshold on the smallest singular value of either arm's Jacobian (default
        1e-3; 0 turns it off).
    singularity_action : {"warn", "stop", "ignore"}
        What a sample below the threshold does (default ``"warn"``).
    stall_time : float
        A run whose path time advances by less than 1% of the time elapsed over a
        window of this length [s] fails as stalled (default 1 s).
    duration_cap : float, optional
        Longest run [s] when the task was slowed; default twice the duration.
    """

    closure: tuple[float, float] = (1e-3, 1e-2)
    tracking: tuple[float, float] = (1e-3, 1e-2)
    singular_value_min: float = 1e-3
    singularity_action: str = "warn"
    stall_time: float = 1.0
    duration_cap: float | None = None

    def __post_init__(self) -> None:
        for name in ("closure", "tracking"):
            pos, rot = getattr(self, name)
            if not (pos > 0 and rot > 0):
                raise InvalidInputError(f"{name} tolerance must be positive, got "
                                        f"{getattr(self, name)}")
        if not (math.isfinite(self.singular_value_min) and self.singular_value_min >= 0):
            raise InvalidInputError("singular_value_min must be a finite number >= 0")
        if self.singularity_action not in SINGULARITY_ACTIONS:
            raise InvalidInputError(f"singularity_action must be one of "
                                    f"{SINGULARITY_ACTIONS}, got {self.singularity_action!r}")
        if not self.stall_time > 0:
            raise InvalidInputError("stall_time must be positive")


__all__ = ["SINGULARITY_ACTIONS", "RunLimits"]
