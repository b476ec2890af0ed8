"""The drive loop's guards from the file's ``cell:`` section, in SI (``docs/robots.md``)."""

from __future__ import annotations

from ..experiments.config import ANGLE_SCALE, TIME_SCALE, ExperimentConfig
from ..experiments.experiment import Experiment
from .loop import DriveSettings

#: The watchdog's default: this many samples of ``dt``.
WATCHDOG_SAMPLES = 3


def drive_settings(cfg: ExperimentConfig, exp: Experiment, *, dry_run: bool) -> DriveSettings:
    """Return the loop's guards from the file's ``cell:`` section, in SI.

    ``watchdog`` is in the file's time unit (default :data:`WATCHDOG_SAMPLES` samples),
    ``start_tolerance`` (default 0.01 rad) and ``range_margin`` in its angle unit.
    """
    c = cfg.cell
    angle, t = ANGLE_SCALE[cfg.units.angle], TIME_SCALE[cfg.units.time]
    dt = exp.options.dt
    return DriveSettings(
        watchdog=WATCHDOG_SAMPLES * dt if c.watchdog is None else c.watchdog * t,
        dry_run=dry_run,
        start_tolerance=0.01 if c.start_tolerance is None else c.start_tolerance * angle,
        range_margin=c.range_margin * angle)


__all__ = ["WATCHDOG_SAMPLES", "drive_settings"]
