"""Run a sweep on Dask: every point once, stored as it finishes, resumable.

:func:`run_sweep` checks every point first (:mod:`.points`: bad input stops the sweep
before anything runs), then lets the :class:`~.driver.Driver` compute the points not
yet stored and writes the table. The sweep folder::

    sweep.json        what the sweep is: file, base, swept keys, points, code digest
    points.jsonl      one JSON line per finished point, keyed by content + code digest
    results.parquet   the results table, one row per point (see :mod:`.table`)
    results.csv       the same table as CSV

``points.jsonl`` is the store of :mod:`dualarm_qp.bench.store` (an append-only file
of whole lines under a file lock), with its claims (:mod:`.claims`): a rerun into the
same folder skips every stored point, and two sweeps run into one folder at the same
time compute each point once. The table is rewritten (atomically) every few seconds
while the sweep runs and once at the end, so it is valid at any moment.

SIGINT or SIGTERM stops the sweep: what finished is stored, the table lists the other
points as ``interrupted``. A scheduler that stops answering ends the sweep the same way,
with :class:`~.driver.SchedulerLost`.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .._io import write_json
from .._signals import InterruptHandlers, signal_name
from ..errors import InvalidInputError
from .claims import STORE_FILE
from .driver import Driver, SchedulerLost
from .labels import file_units, sweep_labels
from .points import PointTask, prepare_points
from .spec import SweepSpec

META_FILE = "sweep.json"


@dataclass(frozen=True)
class SweepSettings:
    """Where and how a sweep runs.

    Parameters
    ----------
    workers : int, optional
        Worker processes of the embedded cluster (default: one per core).
    scheduler : str, optional
        Address of an existing Dask scheduler (``tcp://host:port``).
    batch : int, optional
        Points per task (default: :func:`batch_size`).
    progress : bool
        Show a progress bar on standard error.
    """

    workers: int | None = None
    scheduler: str | None = None
    batch: int | None = None
    progress: bool = False

    def __post_init__(self) -> None:
        for name in ("workers", "batch"):
            value = getattr(self, name)
            if value is not None and not (isinstance(value, int) and value >= 1):
                raise InvalidInputError(f"--{name} must be a whole number >= 1, got {value!r}")
        if self.workers is not None and self.scheduler is not None:
            raise InvalidInputError("give --workers or --scheduler, not both")


@dataclass
class SweepResult:
    """What :func:`run_sweep` did.

    Attributes
    ----------
    out : Path
        The sweep folder.
    rows : list of dict
        The results table (every point; unfinished ones ``interrupted``).
    planned : int
        Points in the sweep.
    computed : int
        Points computed by this run (the others were stored before, or are unfinished).
    interrupted : str or None
        The signal that stopped the sweep (``"SIGINT"``, ``"SIGTERM"``), or None.
    unrun : dict
        Point key -> why it was left unrun (lost with its workers, scheduler lost).
    """

    out: Path
    rows: list[dict[str, Any]]
    planned: int
    computed: int = 0
    interrupted: str | None = None
    unrun: dict[str, str] = field(default_factory=dict)

    @property
    def failures(self) -> list[dict[str, Any]]:
        """Rows of the points that ran and failed."""
        return [r for r in self.rows if r["status"] == "failed"]

    @property
    def finished(self) -> int:
        """Points with a stored record."""
        return sum(r["status"] != "interrupted" for r in self.rows)


def check_sweep_folder(out: Path) -> Path:
    """Return ``out`` if it is new, empty or a sweep folder; refuse any other folder.

    Raises
    ------
    InvalidInputError
        ``out`` holds files but no sweep (a sweep would mix its files with them).
    """
    if out.is_dir() and any(out.iterdir()) and not (
            (out / META_FILE).exists() or (out / STORE_FILE).exists()):
        raise InvalidInputError(f"{out} holds other files and no sweep; give a new folder, "
                                "or the folder of an earlier sweep to resume it")
    return out


def _meta(spec: SweepSpec, tasks: Sequence[PointTask], code: str) -> dict[str, Any]:
    units = file_units(tasks[0].document)
    return {"name": spec.name, "sweep_file": spec.path, "base": str(spec.base),
            "description": spec.description, "swept_keys": spec.swept_keys,
            "map_keys": spec.axes, "paired": spec.paired,
            "units": units, "labels": sweep_labels(spec.swept_keys, units, spec.labels),
            "set": spec.fixed, "grid": spec.grid, "random_n": spec.random_n,
            "random_seed": spec.random_seed, "repeat": spec.repeat, "points": len(tasks),
            "code": code}


def run_sweep(
    spec: SweepSpec,
    out: str | Path,
    *,
    settings: SweepSettings | None = None,
    log: Callable[[str], None] | None = None,
) -> SweepResult:
    """Run every point of ``spec`` not yet stored in ``out``; write the table.

    Parameters
    ----------
    spec : SweepSpec
        The sweep (:func:`~.spec.load_sweep`).
    out : path
        The sweep folder (created if missing); points stored there are reused.
    settings : SweepSettings, optional
        Cluster, batch size, progress bar.
    log : callable, optional
        Receives one line when the points are checked, and one when the sweep waits for
        another sweep on the same folder to finish the points it has claimed.

    Returns
    -------
    SweepResult
        Also when interrupted (``interrupted`` set; the table is written).

    Raises
    ------
    ConfigError
        A bad key or value in the sweep (before anything runs).
    InvalidInputError
        The cluster cannot be reached, or a worker runs other code.
    SchedulerLost
        The scheduler went away mid-sweep (what finished is stored and in the table).
    """
    from ..bench.runner import code_digest

    settings = settings or SweepSettings()
    code = code_digest()
    folder = Path(out)
    tasks = prepare_points(spec, code)
    folder.mkdir(parents=True, exist_ok=True)
    write_json(folder / META_FILE, _meta(spec, tasks, code))
    drv = Driver(tasks, spec.swept_keys, folder, workers=settings.workers,
                 scheduler=settings.scheduler, batch=settings.batch, log=log)
    todo = drv.todo()
    if log is not None:
        log(f"sweep {spec.name}: {len(tasks)} points, {len(tasks) - len(todo)} stored in "
            f"{folder}, {len(todo)} to run")
    with InterruptHandlers() as handlers:
        try:
            if settings.progress:
                from tqdm import tqdm

                drv.bar = tqdm(total=len(tasks), initial=len(tasks) - len(todo),
                               desc=spec.name, unit="pt", file=sys.stderr, leave=True)
            drv.run(code)
            drv.refresh()  # what another sweep on the folder stored meanwhile
        except KeyboardInterrupt as err:
            signum = handlers.signum or getattr(err, "signum", None)
            name = signal_name(signum)
            rows = drv.write_table(f"sweep interrupted ({name})")
            return SweepResult(folder, rows, len(tasks), drv.computed, interrupted=name)
        except SchedulerLost:
            drv.write_table("the scheduler stopped answering")
            raise
        except BaseException:
            drv.write_table()
            raise
        finally:
            if drv.bar is not None:
                drv.bar.close()
    reasons = set(drv.unrun.values())
    rows = drv.write_table("; ".join(sorted(reasons)) if reasons else "not run")
    return SweepResult(folder, rows, len(tasks), drv.computed, unrun=drv.unrun)
