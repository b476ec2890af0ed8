"""Why a run failed: the criteria a run is judged on, and the failure that names one."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

#: Criteria a run can fail on (``Failure.criterion``).
CRITERIA = ("unreachable", "path_collision", "solver", "support", "closure", "tracking",
            "singularity", "stalled", "path_incomplete",
            "range", "speed", "acceleration", "jerk", "collision", "torque", "interrupted",
            "watchdog", "start", "cell")  # the last three: a drive's (docs/robots.md)

#: Criteria whose failure message names its cause (:mod:`.diagnosis`).
EXPLAINED = ("closure", "tracking", "stalled", "path_incomplete")


@dataclass(frozen=True)
class Failure:
    """Why a run failed.

    Attributes
    ----------
    criterion : str
        One of :data:`CRITERIA`.
    sample : int
        Row of the trace where it was found.
    t : float
        Time of that sample [s].
    amount : float
        The offending value (an error [m or rad], a ratio, a singular value, a share of
        the path); NaN when there is none (a solver message).
    limit : float
        What it was allowed.
    message : str
        One line for a person.
    """

    criterion: str
    sample: int
    t: float
    amount: float
    limit: float
    message: str

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready."""
        return {"criterion": self.criterion, "sample": self.sample, "t_s": self.t,
                "amount": self.amount, "limit": self.limit, "message": self.message}


def at(k: int, t: float) -> str:
    """Where a sample's message happens: ``"step 12 at t = 0.1200 s"`` (made only when needed)."""
    return f"step {k} at t = {t:.4f} s"


__all__ = ["CRITERIA", "EXPLAINED", "Failure", "at"]
