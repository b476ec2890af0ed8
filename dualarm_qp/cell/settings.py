"""What the drive loop (:mod:`.loop`) is given and gives back: its guards and its result."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from ..control.rollout import RolloutResult


@dataclass(frozen=True)
class DriveSettings:
    """How the loop guards the cell.

    Parameters
    ----------
    watchdog : float
        Oldest state the controller may act on, on the cell's clock [s].
    dry_run : bool
        Read the robots and compute the commands, but send nothing.
    start_tolerance : float
        Largest distance of a measured joint from the file's start [rad].
    range_margin : float
        How far a measured joint may be outside its range before the cell stops [rad].
    """

    watchdog: float
    dry_run: bool = False
    start_tolerance: float = 0.01
    range_margin: float = 0.0


@dataclass
class DriveResult:
    """What the loop did: the run as ``run`` reports it, and the cell's own record.

    Attributes
    ----------
    result : RolloutResult
        The recorded samples (control samples, then the stop's), the failure if any and
        the realised limits of the control samples.
    columns : dict
        The cell's columns of ``trajectory.csv`` (:func:`.record.cell_columns`).
    cell : dict
        The cell's part of ``summary.json`` (watchdog, clamp, stop, clock).
    """

    result: RolloutResult
    columns: dict[str, Any]
    cell: dict[str, Any] = field(default_factory=dict)


__all__ = ["DriveResult", "DriveSettings"]
