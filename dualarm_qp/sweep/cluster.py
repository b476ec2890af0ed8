"""The Dask cluster a sweep runs on: an embedded local one, or an existing one.

The embedded default is a :class:`distributed.LocalCluster` of ``workers`` single-threaded
worker processes (one per core unless told otherwise): rollouts are pure Python and
NumPy, so processes, not threads, give parallelism. With ``scheduler`` the sweep connects
to a running scheduler (``dask scheduler`` on one machine, ``dask worker ADDRESS`` on
each machine that computes; every worker needs the same dualarm_qp installed).

Dask's own log lines (a worker lost, a reconnect attempt) are kept off the terminal
while the sweep runs: the sweep reports what matters itself.

Starting and closing the embedded cluster are never cut short by SIGINT or SIGTERM: a
signal that comes meanwhile is held (:class:`~dualarm_qp._signals.SignalHold`) and acted
on once the cluster is up, or closed (a second or so). A cluster interrupted half-started
cannot be closed (Dask's exit hook then fails with a traceback), and one interrupted
half-closed is closed again by that hook, which waits 10 s for it.
"""

from __future__ import annotations

import contextlib
import logging
import os
import warnings
from collections.abc import Iterator
from typing import Any

from .._signals import SignalHold
from ..errors import InvalidInputError

#: Seconds to wait for an existing scheduler to answer, and for its first worker.
CONNECT_TIMEOUT_S = 15.0


def default_workers() -> int:
    """Return the cores this process may use (at least 1)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on Linux
        return max(1, os.cpu_count() or 1)


DASK_LOGGERS = ("distributed", "dask", "tornado")


@contextlib.contextmanager
def quiet_dask_logs(level: int = logging.CRITICAL, *, restore: bool = True) -> Iterator[None]:
    """Raise the level of Dask's loggers for the block, then restore it.

    With ``restore`` False the level stays raised (a command that ends after the block:
    a client closed on a lost scheduler still logs from its background thread).
    """
    import distributed  # noqa: F401  (its import sets up its loggers: quiet them after)

    names = [n for n in list(logging.root.manager.loggerDict)
             if any(n == d or n.startswith(d + ".") for d in DASK_LOGGERS)]
    loggers = [logging.getLogger(n) for n in sorted({*DASK_LOGGERS, *names})]
    before = [lg.level for lg in loggers]
    for lg in loggers:
        lg.setLevel(level)
    try:
        yield
    finally:
        if restore:
            for lg, old in zip(loggers, before, strict=True):
                lg.setLevel(old)


def _connect(address: str) -> Any:
    from distributed import Client

    if "://" not in address or not address.split("://", 1)[1]:
        raise InvalidInputError(f"--scheduler takes an address such as tcp://host:8786, "
                                f"got {address!r}")
    try:
        client = Client(address, timeout=CONNECT_TIMEOUT_S, set_as_default=False)
    except (OSError, TimeoutError, ValueError) as err:
        raise InvalidInputError(f"cannot reach the Dask scheduler at {address}: "
                                f"{type(err).__name__}: {err}") from None
    try:
        client.wait_for_workers(1, timeout=CONNECT_TIMEOUT_S)
    except (OSError, TimeoutError) as err:
        client.close()
        raise InvalidInputError(f"the Dask scheduler at {address} has no worker (waited "
                                f"{CONNECT_TIMEOUT_S:g} s); start one with 'dask worker "
                                f"{address} --nthreads 1'") from err
    return client


@contextlib.contextmanager
def open_client(*, workers: int | None = None, scheduler: str | None = None) -> Iterator[Any]:
    """Yield a :class:`distributed.Client` for the sweep; close what was opened.

    Parameters
    ----------
    workers : int, optional
        Worker processes of the embedded cluster (default: :func:`default_workers`).
    scheduler : str, optional
        Address of an existing scheduler (``tcp://host:port``); no cluster is started.

    Raises
    ------
    InvalidInputError
        A bad address, a scheduler that does not answer or has no worker, or a bad
        worker count.
    """
    if workers is not None and scheduler is not None:
        raise InvalidInputError("give --workers or --scheduler, not both")
    if workers is not None and workers < 1:
        raise InvalidInputError(f"--workers must be at least 1, got {workers}")
    from distributed import Client

    cluster: Any = None
    client: Any = None
    try:
        if scheduler is not None:  # nothing of ours to close if cut short: no hold
            client = _connect(scheduler)
        else:
            with SignalHold():  # started whole (see the module docstring), then stopped
                cluster = _local_cluster(workers or default_workers())
                client = Client(cluster, set_as_default=False)
        yield client
    finally:
        with SignalHold():  # closed whole, then stopped
            for what, timeout in ((client, 5), (cluster, 10)):
                if what is not None:
                    with contextlib.suppress(Exception):
                        what.close(timeout=timeout)


def _local_cluster(workers: int) -> Any:
    from distributed import LocalCluster

    with warnings.catch_warnings():  # "port 8787 in use": no dashboard is needed
        warnings.filterwarnings("ignore", message="Port .* is already in use")
        return LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                            dashboard_address=None, silence_logs=logging.CRITICAL)


def worker_count(client: Any) -> int:
    """Workers connected to the client's scheduler now (at least 1)."""
    try:
        return max(1, len(client.scheduler_info().get("workers", {})))
    except Exception:  # a scheduler that went away: the caller finds out on its own
        return 1
