"""Sweeps: run an experiment over a grid or a random sample of its settings, on Dask.

A sweep file (:mod:`.spec`) names a base experiment file and the keys to vary; every
point is checked like a run's file (:mod:`.points`), run by Dask workers in batches
(:mod:`.worker`, :mod:`.cluster`), stored as it finishes so a sweep resumes
(:mod:`.runner`), and summed up in a results table (:mod:`.table`) and an HTML report
with maps (:mod:`.report`, :mod:`.maps`).

Importing this package imports neither Dask, pyarrow nor matplotlib: they are imported
when a sweep runs or a report is drawn.
"""

from .runner import SchedulerLost, SweepResult, SweepSettings, run_sweep
from .spec import Point, SweepSpec, expand, load_sweep

__all__ = [
    "Point",
    "SchedulerLost",
    "SweepResult",
    "SweepSettings",
    "SweepSpec",
    "expand",
    "load_sweep",
    "run_sweep",
]
