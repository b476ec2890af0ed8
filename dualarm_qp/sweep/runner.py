"""Run a sweep on Dask: every point once, stored as it finishes, resumable.

The process that runs :func:`run_sweep` (the *driver*) checks every point first
(:mod:`.points`: bad input stops the sweep before anything runs), then sends the points
not yet stored to the workers in batches (:func:`~.worker.run_batch`), and stores each
point's record as its batch comes back. The driver is the only writer of the sweep
folder::

    sweep.json        what the sweep is: file, base, swept keys, points, code digest
    points.jsonl      one JSON line per finished point, keyed by content + code digest
    results.parquet   the results table, one row per point (see :mod:`.table`)
    results.csv       the same table as CSV

``points.jsonl`` is the store of :mod:`dualarm_qp.bench.store` (an append-only file
of whole lines under a file lock). A rerun into the same folder skips every stored
point. The table is rewritten (atomically) every few seconds while the sweep runs and
once at the end, so it is valid at any moment.

Faults: a worker that dies takes its batch with it; the scheduler gives the batch to
another worker, and its records are stored once, when the batch comes back. A batch lost
with its worker :data:`MAX_WORKER_LOSSES` times is left unrun (Dask's ``KilledWorker``):
the sweep ends with exit 1 and a rerun resumes. SIGINT or SIGTERM stops the sweep: what
finished is stored, the table lists the other points as ``interrupted``. A scheduler
that stops answering ends the sweep the same way, with :class:`SchedulerLost`.
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import math
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .._io import write_json
from .._signals import InterruptHandlers, SignalHold, signal_name
from ..bench.store import append_result, load_results
from ..errors import DualArmError, InvalidInputError
from .cluster import open_client, quiet_dask_logs, worker_count
from .points import PointTask, prepare_points
from .spec import SweepSpec
from .table import build_rows, write_table
from .worker import run_batch, run_point

STORE_FILE = "points.jsonl"
META_FILE = "sweep.json"

#: Seconds between rewrites of the results table while the sweep runs.
TABLE_EVERY_S = 5.0

#: Seconds the scheduler may stay unreachable before the sweep gives up on it.
SCHEDULER_GRACE_S = 10.0

#: Seconds between looks at the batches under way.
POLL_S = 0.1

#: Times a batch may be lost with its worker before it is left unrun.
MAX_WORKER_LOSSES = 3

#: Batches per worker the points are split into (more: better balance at the end).
BATCHES_PER_WORKER = 4

#: Most points in one batch.
MAX_BATCH = 16


class SchedulerLost(DualArmError):
    """The Dask scheduler stopped answering during a sweep (what finished is stored)."""


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


def batch_size(todo: int, workers: int) -> int:
    """Return the points per task.

    About :data:`BATCHES_PER_WORKER` tasks per worker, at most :data:`MAX_BATCH` points
    each: a task costs the scheduler about a millisecond, a point's rollout a tenth of a
    second or more.
    """
    return max(1, min(MAX_BATCH, math.ceil(todo / (BATCHES_PER_WORKER * max(1, workers)))))


def _meta(spec: SweepSpec, tasks: Sequence[PointTask], code: str) -> dict[str, Any]:
    return {"name": spec.name, "sweep_file": spec.path, "base": str(spec.base),
            "description": spec.description, "swept_keys": spec.swept_keys,
            "set": spec.fixed, "grid": spec.grid, "random_n": spec.random_n,
            "random_seed": spec.random_seed, "repeat": spec.repeat, "points": len(tasks),
            "code": code}


class _Driver:
    """The driver's state: the store, the records and the table."""

    def __init__(self, spec: SweepSpec, tasks: list[PointTask], out: Path,
                 settings: SweepSettings) -> None:
        self.spec, self.tasks, self.out, self.settings = spec, tasks, out, settings
        self.store = out / STORE_FILE
        keys = {t.key for t in tasks}
        self.records = {k: r for k, r in load_results(self.store).items() if k in keys}
        self.computed = 0
        self.unrun: dict[str, str] = {}
        self.written_at = time.monotonic()
        self.bar: Any = None
        self._last_failure = ""

    def todo(self) -> list[PointTask]:
        return [t for t in self.tasks if t.key not in self.records]

    def store_records(self, recs: Sequence[dict[str, Any]]) -> None:
        """Store finished records once each (an interrupted rollout is not stored)."""
        with SignalHold():  # a finished record is stored whole
            for rec in recs:
                if rec["status"] == "interrupted" or rec["key"] in self.records:
                    continue
                append_result(self.store, rec)
                self.records[rec["key"]] = rec
                self.computed += 1
                if self.bar is not None:
                    self.bar.update(1)
            if self.bar is not None:
                failed = sum(r["status"] == "failed" for r in self.records.values())
                self.bar.set_postfix_str(f"failed {failed}", refresh=False)
        if time.monotonic() - self.written_at > TABLE_EVERY_S:
            self.write_table()

    def rows(self, reason: str = "not run") -> list[dict[str, Any]]:
        return build_rows(self.tasks, self.spec.swept_keys, self.records, reason)

    def write_table(self, reason: str = "not run") -> list[dict[str, Any]]:
        rows = self.rows(reason)
        with SignalHold():
            write_table(self.out, rows, self.spec.swept_keys)
        self.written_at = time.monotonic()
        return rows

    def run_remote(self, todo: list[PointTask], code: str) -> None:
        """Send ``todo`` to the cluster in batches; store each batch as it returns."""
        with quiet_dask_logs(), open_client(workers=self.settings.workers,
                                            scheduler=self.settings.scheduler) as client:
            size = self.settings.batch or batch_size(len(todo), worker_count(client))
            batches = [todo[i:i + size] for i in range(0, len(todo), size)]
            pending = {client.submit(run_batch, b, code, pure=False): b for b in batches}
            self._collect(client, pending, code)

    def _collect(self, client: Any, pending: dict[Any, list[PointTask]], code: str) -> None:
        from distributed import as_completed

        finished = as_completed(list(pending), loop=client.loop)
        resent: dict[tuple[str, ...], int] = {}
        lost_since: float | None = None
        while pending:
            done = finished.next_batch(block=False)
            if not done:
                time.sleep(POLL_S)
            # Futures are cancelled here only when the scheduler went away.
            cancelled = any(f.status == "cancelled" for f in done)
            if client.status != "running" or cancelled:
                lost_since = lost_since or time.monotonic()
                if cancelled or time.monotonic() - lost_since > SCHEDULER_GRACE_S:
                    self._give_up(pending, "the scheduler stopped answering")
                    raise SchedulerLost(
                        f"the Dask scheduler stopped answering (client {client.status}); "
                        f"{len(self.records)} of {len(self.tasks)} points are stored in "
                        f"{self.out}; run the same command again (with a running "
                        "scheduler) to resume")
            else:
                lost_since = None
            for fut in done:
                batch = pending.pop(fut)
                if self._finish(fut, batch):
                    continue
                # A transient failure (a connection cut while the worker died, say):
                # send the batch again, a few times at most.
                ids = tuple(t.key for t in batch)
                resent[ids] = resent.get(ids, 0) + 1
                if resent[ids] > MAX_WORKER_LOSSES:
                    for t in batch:
                        self.unrun[t.key] = (f"its task failed {MAX_WORKER_LOSSES + 1} times "
                                             f"({self._last_failure})")
                    continue
                again = client.submit(run_batch, batch, code, pure=False)
                pending[again] = batch
                finished.add(again)

    def _finish(self, fut: Any, batch: list[PointTask]) -> bool:
        """Store a finished batch; return False when it should be sent again.

        A batch lost with its worker more often than Dask allows (``KilledWorker``) is
        left unrun; a worker running other code stops the sweep (bad set-up).
        """
        from distributed import KilledWorker

        try:
            if fut.status == "finished":
                self.store_records(fut.result())
                return True
            failure = fut.exception() if fut.status == "error" else None
        except (OSError, asyncio.CancelledError, concurrent.futures.CancelledError) as lost:
            # The result cannot be fetched, or the future was cancelled under us: the
            # scheduler is gone (Dask cancels every future when it loses it).
            raise SchedulerLost(f"the Dask scheduler stopped answering ({type(lost).__name__}"
                                f"); {len(self.records)} of {len(self.tasks)} points are "
                                f"stored in {self.out}; run the same command again (with a "
                                "running scheduler) to resume") from None
        if isinstance(failure, DualArmError):  # a worker running other code
            raise failure
        if isinstance(failure, KilledWorker):
            for t in batch:
                self.unrun[t.key] = f"lost with its worker {MAX_WORKER_LOSSES} times"
            return True
        self._last_failure = type(failure).__name__ if failure else fut.status
        return False

    def _give_up(self, pending: dict[Any, list[PointTask]], reason: str) -> None:
        for batch in pending.values():
            for t in batch:
                self.unrun[t.key] = reason
        pending.clear()


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
        Receives one line when the points are checked.

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
    drv = _Driver(spec, tasks, folder, settings)
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
            drv.store_records([run_point(t) for t in todo if t.start_failure is not None])
            remote = [t for t in todo if t.start_failure is None]
            if remote:
                drv.run_remote(remote, code)
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
