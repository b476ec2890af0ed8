"""Append-only result store shared by concurrent benches: one JSON line per finished job.

Layout of a bench folder::

    results.jsonl     one JSON line per finished job (its "key" field names the job)
    .lock             flock'ed while the store is read or appended to
    .claims/<key>     flock'ed by the bench computing that job

Each line is written with a single ``write`` on a file opened for appending, under an
exclusive :func:`fcntl.flock` of ``.lock``, and flushed to disk; a bench killed in the
middle of a write leaves at worst a torn last line without its newline, which
:func:`load_results` cuts off (in place, under the same lock: no temporary file).

A job is *claimed* before it is computed (:func:`claim_job`): an exclusive flock of
``.claims/<key>``, held until the job is stored. Another bench on the same folder that
finds the claim taken leaves the job to its owner and, once it has run everything else,
waits for the claim; the kernel releases it when its owner exits, however it exits, so a
crashed or interrupted bench never blocks the job for good. Whoever holds a claim reads
the store again before computing, so a job is computed and stored once. A claim file is
removed only once its job is stored.
"""

from __future__ import annotations

import contextlib
import fcntl
import json
import os
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from .._io import jsonable

LOCK_FILE = ".lock"
CLAIMS_DIR = ".claims"


@contextlib.contextmanager
def locked(folder: Path) -> Iterator[None]:
    """Hold the exclusive lock of the store in ``folder`` (created if missing)."""
    folder.mkdir(parents=True, exist_ok=True)
    fd = os.open(folder / LOCK_FILE, os.O_RDWR | os.O_CREAT, 0o644)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)  # closing releases the lock


def append_result(path: Path, record: dict[str, Any]) -> None:
    """Append ``record`` as one JSON line to ``path`` (created if missing), under the lock."""
    line = (json.dumps(jsonable(record), separators=(",", ":")) + "\n").encode("utf-8")
    with locked(path.parent):
        fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_APPEND, 0o644)
        try:
            _repair(fd)
            os.write(fd, line)
            os.fsync(fd)
        finally:
            os.close(fd)


def _repair(fd: int) -> None:
    """Cut a torn last line (no newline) off the open store ``fd`` (lock held)."""
    size = os.fstat(fd).st_size
    if not size or os.pread(fd, 1, size - 1) == b"\n":
        return
    data = os.pread(fd, size, 0)
    os.ftruncate(fd, data.rfind(b"\n") + 1)


def load_results(path: Path) -> dict[str, dict[str, Any]]:
    """Finished jobs stored in ``path``, by their ``"key"`` field (later lines win).

    A last line without its newline (a write cut short) is ignored and cut from the
    file; a line that is not valid JSON is ignored. Reads under the store's lock.
    """
    if not path.exists():
        return {}
    with locked(path.parent):
        fd = os.open(path, os.O_RDWR)
        try:
            _repair(fd)
            data = os.pread(fd, os.fstat(fd).st_size, 0)
        finally:
            os.close(fd)
    out: dict[str, dict[str, Any]] = {}
    for raw in data.splitlines():
        try:
            rec = json.loads(raw)
        except ValueError:
            continue
        if isinstance(rec, dict) and isinstance(rec.get("key"), str):
            out[rec["key"]] = rec
    return out


class Claim:
    """An exclusive claim on one job of a store (see the module docstring).

    Attributes
    ----------
    path : Path
        The claim file ``.claims/<key>``.
    """

    def __init__(self, path: Path, fd: int) -> None:
        self.path = path
        self._fd: int | None = fd

    def release(self, *, stored: bool) -> None:
        """Give the claim up; remove its file when the job is in the store (``stored``).

        A claim given up on a job that is not stored (interrupted, failed) keeps its
        file, so that a bench waiting on it sees the job is still to be done.
        """
        if self._fd is None:
            return
        try:
            if stored:
                self.path.unlink(missing_ok=True)
        finally:
            os.close(self._fd)
            self._fd = None

    def __enter__(self) -> Claim:
        return self

    def __exit__(self, *exc: object) -> None:
        self.release(stored=False)


def claim_job(folder: Path, key: str, *, wait: bool) -> Claim | None:
    """Claim job ``key`` of the store in ``folder``.

    Parameters
    ----------
    folder : Path
        The bench folder.
    key : str
        The job's key (a hex digest: a safe file name).
    wait : bool
        Block until the claim is free (a signal still interrupts the wait); otherwise
        return None at once when another process holds it.

    Returns
    -------
    Claim or None
        The claim, held until released (or until this process exits).
    """
    claims = folder / CLAIMS_DIR
    claims.mkdir(parents=True, exist_ok=True)
    path = claims / key
    fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | (0 if wait else fcntl.LOCK_NB))
    except BlockingIOError:
        os.close(fd)
        return None
    except BaseException:
        os.close(fd)
        raise
    with contextlib.suppress(OSError):  # who holds it, for a person looking at the folder
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
    return Claim(path, fd)
