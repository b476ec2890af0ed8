"""The driver of a sweep: points claimed, sent to Dask in batches, stored as they return.

The process that runs a sweep (the *driver*) keeps a queue of the points not yet stored.
It claims a batch of them (:mod:`.claims`: another sweep on the same folder then leaves
them alone), sends the batch to the cluster (:func:`~.worker.run_batch`) and stores each
record as its batch comes back; a point whose start cannot be reached is recorded by the
driver itself. Only a few batches per worker are under way at a time, so the claims held
stay few. Points claimed by another sweep are looked at again once this one has nothing
else to do: stored by then, they are taken from the store; left unfinished (that sweep
was stopped), they are computed here.

Faults: a worker that dies takes its batch with it; the scheduler gives the batch to
another worker, and its records are stored once, when the batch comes back. A batch lost
with its worker :data:`MAX_WORKER_LOSSES` times is left unrun (Dask's ``KilledWorker``).
A scheduler that stops answering ends the sweep with :class:`SchedulerLost`.
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import contextlib
import math
import time
from collections import deque
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from .._signals import SignalHold, raise_if_interrupted
from ..errors import DualArmError
from .claims import PointStore, claims_cap
from .cluster import open_client, quiet_dask_logs, worker_count
from .points import PointTask
from .table import build_rows, write_table
from .worker import run_batch, run_point

#: Seconds between rewrites of the results table while the sweep runs.
TABLE_EVERY_S = 5.0

#: Seconds the scheduler may stay unreachable before the sweep gives up on it.
SCHEDULER_GRACE_S = 10.0

#: Seconds between looks at the batches under way.
POLL_S = 0.1

#: Seconds between looks at the points another sweep on the same folder has claimed.
OTHERS_POLL_S = 1.0

#: Times a batch may be lost with its worker before it is left unrun.
MAX_WORKER_LOSSES = 3

#: Batches per worker the points are split into (more: better balance at the end).
BATCHES_PER_WORKER = 4

#: Batches per worker under way at a time (one running, one waiting).
IN_FLIGHT_PER_WORKER = 2

#: Most points in one batch.
MAX_BATCH = 16


class SchedulerLost(DualArmError):
    """The Dask scheduler stopped answering during a sweep (what finished is stored)."""


def batch_size(todo: int, workers: int) -> int:
    """Return the points per task when ``todo`` points are left.

    About :data:`BATCHES_PER_WORKER` tasks per worker, at most :data:`MAX_BATCH` points
    each: a task costs the scheduler about a millisecond, a point's rollout a tenth of a
    second or more. Asked again at every batch, with the points left: the batches shrink
    towards the end of a sweep, down to one point, so that no worker waits long for
    the last batch of another.
    """
    return max(1, min(MAX_BATCH, math.ceil(todo / (BATCHES_PER_WORKER * max(1, workers)))))


class Driver:
    """The driver's state: the store and its claims, the records, the table.

    Parameters
    ----------
    tasks : list of PointTask
        The sweep's points.
    swept : sequence of str
        The swept keys (the table's value columns).
    out : Path
        The sweep folder.
    workers, scheduler, batch
        Where and how to run (see :class:`~.runner.SweepSettings`).
    log : callable, optional
        Receives a line when the sweep waits for another one on the same folder.
    """

    def __init__(self, tasks: list[PointTask], swept: Sequence[str], out: Path, *,
                 workers: int | None = None, scheduler: str | None = None,
                 batch: int | None = None, log: Callable[[str], None] | None = None
                 ) -> None:
        self.tasks, self.swept, self.out = tasks, list(swept), out
        self.workers, self.scheduler, self.batch = workers, scheduler, batch
        self.log = log
        self.store = PointStore(out)
        self.keys = {t.key for t in tasks}
        self.records: dict[str, dict[str, Any]] = {}
        self.computed = 0
        self.unrun: dict[str, str] = {}
        self.written_at = time.monotonic()
        self.bar: Any = None
        self._last_failure = ""
        self.refresh()

    # -- the store ---------------------------------------------------------------------

    def refresh(self) -> None:
        """Take the records stored since the last look (by this sweep or another one)."""
        new = {k: r for k, r in self.store.read_new().items()
               if k in self.keys and k not in self.records}
        self.records.update(new)
        self._progress(len(new))

    def todo(self) -> list[PointTask]:
        """Return the points with no record yet, in order."""
        return [t for t in self.tasks if t.key not in self.records]

    def store_records(self, recs: Sequence[dict[str, Any]]) -> None:
        """Store finished records once each (an interrupted rollout is not stored)."""
        with SignalHold():  # a finished record is stored whole
            added = 0
            for rec in recs:
                key = rec["key"]
                if rec["status"] == "interrupted" or key in self.records:
                    self.store.release(key, stored=key in self.records)
                    continue
                self.store.store(rec)
                self.records[key] = rec
                self.computed += 1
                added += 1
            self._progress(added)
        if time.monotonic() - self.written_at > TABLE_EVERY_S:
            self.write_table()

    def _progress(self, added: int) -> None:
        if self.bar is None or not added:
            return
        self.bar.update(added)
        failed = sum(r["status"] == "failed" for r in self.records.values())
        self.bar.set_postfix_str(f"failed {failed}", refresh=False)

    def rows(self, reason: str = "not run") -> list[dict[str, Any]]:
        """Return the results table: every point, those with no record ``interrupted``."""
        return build_rows(self.tasks, self.swept, self.records, reason)

    def write_table(self, reason: str = "not run") -> list[dict[str, Any]]:
        """Write the results table (atomically) and return its rows."""
        rows = self.rows(reason)
        with SignalHold():
            write_table(self.out, rows, self.swept)
        self.written_at = time.monotonic()
        return rows

    def _take(self, queue: deque[PointTask], n: int, others: list[PointTask]
              ) -> list[PointTask]:
        """Claim up to ``n`` points of ``queue`` and return those still to compute.

        A point claimed by another sweep goes to ``others``; one that another sweep
        stored before this one claimed it is taken from the store.
        """
        got: list[PointTask] = []
        while queue and len(got) < n:
            task = queue.popleft()
            if task.key in self.records:
                continue
            if self.store.claim(task.key):
                got.append(task)
            else:
                others.append(task)
        if got:
            self.refresh()
            for task in got:
                if task.key in self.records:
                    self.store.release(task.key, stored=True)
        return [t for t in got if t.key not in self.records]

    # -- the run -----------------------------------------------------------------------

    def run(self, code: str) -> None:
        """Compute every point not stored; return when each is stored or left unrun."""
        queue = deque(self.todo())
        others: list[PointTask] = []  # claimed by another sweep on the folder
        try:
            with contextlib.ExitStack() as stack:
                remote = _Remote(self, stack, code)
                looked = time.monotonic()
                said = False
                while queue or others or remote.pending:
                    # A Ctrl-C whose KeyboardInterrupt something on the way swallowed (a
                    # call into Dask's client when it came) still stops the sweep here.
                    raise_if_interrupted()
                    if remote.client is None and any(t.start_failure is None for t in queue):
                        remote.open(sum(t.start_failure is None for t in queue))
                    while queue and remote.has_room():
                        batch = self._take(queue, remote.batch_for(len(queue)), others)
                        self.store_records([run_point(t) for t in batch
                                            if t.start_failure is not None])
                        remote.submit([t for t in batch if t.start_failure is None])
                    came_back = remote.collect()
                    if others and not queue and time.monotonic() - looked > OTHERS_POLL_S:
                        looked = time.monotonic()
                        self.refresh()
                        queue.extend(t for t in others if t.key not in self.records)
                        others.clear()
                    elif others and not queue and not remote.pending and not said:
                        said = True
                        if self.log is not None:
                            self.log(f"waiting for another sweep on {self.out} to finish "
                                     f"{len(others)} points")
                    if not came_back:
                        time.sleep(POLL_S)
        finally:
            self.store.release_all()


class _Remote:
    """The Dask side of a sweep: the cluster (opened when first needed), batches under way.

    Parameters
    ----------
    driver : Driver
        Where the records go.
    stack : ExitStack
        Closes the cluster when the sweep ends.
    code : str
        The code digest the points are keyed with.
    """

    def __init__(self, driver: Driver, stack: contextlib.ExitStack[Any], code: str) -> None:
        self.driver, self.stack, self.code = driver, stack, code
        self.client: Any = None
        self.pending: dict[Any, list[PointTask]] = {}
        self.size = driver.batch or 1
        self.workers = 1
        self._room = 1
        self._finished: Any = None
        self._resent: dict[tuple[str, ...], int] = {}
        self._lost_since: float | None = None

    def open(self, points: int) -> None:
        """Start or reach the cluster; size the batches for ``points`` points."""
        from distributed import as_completed

        drv = self.driver
        self.stack.enter_context(quiet_dask_logs())
        self.client = self.stack.enter_context(open_client(workers=drv.workers,
                                                           scheduler=drv.scheduler))
        workers = self.workers = worker_count(self.client)
        self.size = drv.batch or batch_size(points, workers)  # the largest batch
        self._room = max(1, min(IN_FLIGHT_PER_WORKER * workers, claims_cap() // self.size))
        self._finished = as_completed([], loop=self.client.loop)

    def batch_for(self, left: int) -> int:
        """Return the points of the next batch with ``left`` points in the queue.

        The size given (``--batch``), or :func:`batch_size` of the points left, never
        more than the first batch (the claims held stay within their cap).
        """
        if self.driver.batch or self.client is None:
            return self.size
        return min(self.size, batch_size(left, self.workers))

    def has_room(self) -> bool:
        """Whether another batch may be taken now.

        Any number while no cluster is open: the points taken are then all recorded by
        the driver.
        """
        return self.client is None or len(self.pending) < self._room

    def submit(self, batch: list[PointTask]) -> None:
        """Send a batch of claimed points to the cluster (nothing for an empty batch)."""
        if not batch:
            return
        fut = self.client.submit(run_batch, batch, self.code, pure=False)
        self.pending[fut] = batch
        self._finished.add(fut)

    def collect(self) -> bool:
        """Store the batches that came back (False: none); raise if the scheduler is gone.

        Raises
        ------
        SchedulerLost
            The scheduler stopped answering (its batches are left unrun).
        """
        if not self.pending:
            return False
        done = self._finished.next_batch(block=False)
        # Futures are cancelled here only when the scheduler went away.
        cancelled = any(f.status == "cancelled" for f in done)
        if self.client.status != "running" or cancelled:
            self._lost_since = self._lost_since or time.monotonic()
            if cancelled or time.monotonic() - self._lost_since > SCHEDULER_GRACE_S:
                self._give_up("the scheduler stopped answering")
                raise self._lost(f"client {self.client.status}")
        else:
            self._lost_since = None
        for fut in done:
            batch = self.pending.pop(fut)
            if self._finish(fut, batch):
                continue
            # A transient failure (a connection cut while the worker died, say): send the
            # batch again, a few times at most.
            ids = tuple(t.key for t in batch)
            self._resent[ids] = self._resent.get(ids, 0) + 1
            if self._resent[ids] > MAX_WORKER_LOSSES:
                self._leave(batch, f"its task failed {MAX_WORKER_LOSSES + 1} times "
                            f"({self.driver._last_failure})")
                continue
            self.submit(batch)
        return bool(done)

    def _lost(self, why: str) -> SchedulerLost:
        drv = self.driver
        return SchedulerLost(f"the Dask scheduler stopped answering ({why}); "
                             f"{len(drv.records)} of {len(drv.tasks)} points are stored in "
                             f"{drv.out}; run the same command again (with a running "
                             "scheduler) to resume")

    def _finish(self, fut: Any, batch: list[PointTask]) -> bool:
        """Store a finished batch; return False when it should be sent again.

        A batch lost with its worker more often than Dask allows (``KilledWorker``) is
        left unrun; a worker running other code stops the sweep (bad set-up).
        """
        from distributed import KilledWorker

        try:
            if fut.status == "finished":
                self.driver.store_records(fut.result())
                return True
            failure = fut.exception() if fut.status == "error" else None
        except (OSError, asyncio.CancelledError, concurrent.futures.CancelledError) as lost:
            # The result cannot be fetched, or the future was cancelled under us: the
            # scheduler is gone (Dask cancels every future when it loses it).
            raise self._lost(type(lost).__name__) from None
        if isinstance(failure, DualArmError):  # a worker running other code
            raise failure
        if isinstance(failure, KilledWorker):
            self._leave(batch, f"lost with its worker {MAX_WORKER_LOSSES} times")
            return True
        self.driver._last_failure = type(failure).__name__ if failure else fut.status
        return False

    def _leave(self, batch: list[PointTask], reason: str) -> None:
        """Leave a batch unrun, its claims given up (a later run computes it)."""
        for t in batch:
            self.driver.unrun[t.key] = reason
            self.driver.store.release(t.key)

    def _give_up(self, reason: str) -> None:
        for batch in self.pending.values():
            self._leave(batch, reason)
        self.pending.clear()
