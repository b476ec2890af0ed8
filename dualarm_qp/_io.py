"""Atomic file output and JSON conversion, shared by the experiment and bench writers.

Every output file is written to a temporary name in its folder and renamed into place,
so a run that fails or is interrupted never leaves a half-written file: a reader sees
either the previous complete file or the new complete one.

A *set* of files (a run's outputs) is written inside a :class:`SignalHold`, which keeps
SIGINT and SIGTERM from cutting the set short and delivers them when it is complete.
The command line installs :class:`InterruptHandlers`, under which both signals raise
KeyboardInterrupt and are remembered even when some code swallows that exception.
"""

from __future__ import annotations

import json
import math
import os
import signal
import tempfile
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from types import FrameType
from typing import IO, Any

import numpy as np


def _umask_mode() -> int:
    """File mode a plain ``open`` would give under the current umask."""
    mask = os.umask(0)
    os.umask(mask)
    return 0o666 & ~mask


@contextmanager
def _temp_beside(path: Path) -> Iterator[str]:
    """Yield a temporary path beside ``path``; rename it onto ``path`` on success."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp: str | None = None
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=path.suffix or ".tmp",
                                   dir=path.parent)
        os.close(fd)
        yield tmp
        os.chmod(tmp, _umask_mode())
        os.replace(tmp, path)
    except BaseException:
        if tmp is not None:
            with SignalHold():  # a second Ctrl-C must not leave the temporary file
                Path(tmp).unlink(missing_ok=True)
        raise


@contextmanager
def atomic_open(path: Path) -> Iterator[IO[str]]:
    """Open a temporary text file beside ``path``; rename it onto ``path`` on success."""
    with _temp_beside(path) as tmp, open(tmp, "w", encoding="utf-8", newline="") as fh:
        yield fh


def atomic_write_with(path: Path, writer: Callable[[str], None]) -> None:
    """Let ``writer(tmp_path)`` write a file (e.g. a plot), then rename it onto ``path``."""
    with _temp_beside(path) as tmp:
        writer(tmp)


def write_text(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` atomically (UTF-8)."""
    with atomic_open(path) as fh:
        fh.write(text)


def jsonable(value: Any) -> Any:
    """Return ``value`` with numpy types made Python ones and non-finite floats None."""
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return jsonable(value.tolist())
    if isinstance(value, (np.floating, float)):
        f = float(value)
        return f if math.isfinite(f) else None
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.bool_):
        return bool(value)
    return value


def write_json(path: Path, data: Any) -> None:
    """Write ``data`` as indented JSON, atomically (non-finite numbers become null)."""
    write_text(path, json.dumps(jsonable(data), indent=2) + "\n")


# Signals -------------------------------------------------------------------------------

#: The signals that stop a run: Ctrl-C, and ``kill``'s default.
STOP_SIGNALS: tuple[signal.Signals, ...] = (signal.SIGINT, signal.SIGTERM)


def _settable(sig: signal.Signals) -> bool:
    """Whether to take ``sig`` over: main thread, and not ignored or set outside Python."""
    if threading.current_thread() is not threading.main_thread():
        return False
    current = signal.getsignal(sig)
    return current is not None and current is not signal.SIG_IGN


def _take_over(previous: dict[signal.Signals, Any], handler: Any) -> None:
    """Install ``handler`` for the stop signals, remembering the handlers in ``previous``.

    A signal that comes half-way (to a handler that raises) leaves nothing changed.
    """
    try:
        for sig in STOP_SIGNALS:
            if _settable(sig):
                previous[sig] = signal.getsignal(sig)
                signal.signal(sig, handler)
    except BaseException:
        for sig, old in previous.items():
            signal.signal(sig, old)
        previous.clear()
        raise


class SignalHold:
    """Hold SIGINT and SIGTERM while a block runs, so that they cannot cut it short.

    Use as a context manager around writing a set of files: a signal received inside
    the block is remembered, and delivered to the handler that was in place before
    once the block ends (with Python's default handler: KeyboardInterrupt; with the
    default action of SIGTERM: the process ends, its files complete). Holds nest.
    Outside the main thread, or for a signal the process ignores, nothing changes.

    Parameters
    ----------
    deliver : bool
        Deliver a held signal when the block ends (default); with False the caller
        calls :meth:`deliver` when it is ready (a block that raises delivers at once).

    Attributes
    ----------
    signum : int or None
        The first signal held and not yet delivered.
    """

    def __init__(self, *, deliver: bool = True) -> None:
        self.signum: int | None = None
        self._deliver_on_exit = deliver
        self._previous: dict[signal.Signals, Any] = {}

    def _hold(self, signum: int, frame: FrameType | None) -> None:
        if self.signum is None:
            self.signum = signum

    def __enter__(self) -> SignalHold:
        _take_over(self._previous, self._hold)
        return self

    def __exit__(self, exc_type: type[BaseException] | None, *exc: object) -> None:
        for sig, previous in self._previous.items():
            signal.signal(sig, previous)
        self._previous.clear()
        if self._deliver_on_exit or exc_type is not None:
            self.deliver()

    def deliver(self) -> None:
        """Deliver the held signal, if any, to the process's handler (it may raise)."""
        signum, self.signum = self.signum, None
        if signum is not None:
            signal.raise_signal(signum)


class InterruptHandlers:
    """Make SIGINT and SIGTERM raise KeyboardInterrupt, and remember that they came.

    The command line runs inside this context manager, so that ``kill`` (SIGTERM) stops
    a run the way Ctrl-C does, and an interrupt that some code swallowed (a
    KeyboardInterrupt raised inside a weak-reference callback, or turned into an
    ImportError by an extension module) is still known: see :func:`interrupt_requested`.
    The previous handlers come back on exit. A signal the process inherited as ignored
    (SIGINT in a background job of a non-interactive shell) stays ignored.

    Parameters
    ----------
    final : bool
        The process ends after the block: leave the signals at their default action
        (end the process) instead of restoring the previous handlers, so that a signal
        during interpreter shutdown ends it quietly, not with a traceback.

    Attributes
    ----------
    signum : int or None
        The first signal received while installed.
    """

    def __init__(self, *, final: bool = False) -> None:
        self.signum: int | None = None
        self._final = final
        self._previous: dict[signal.Signals, Any] = {}

    def __call__(self, signum: int, frame: FrameType | None) -> None:
        if self.signum is None:
            self.signum = signum
        raise KeyboardInterrupt(signal.Signals(signum).name)

    def __enter__(self) -> InterruptHandlers:
        _take_over(self._previous, self)
        _ACTIVE.append(self)
        return self

    def __exit__(self, *exc: object) -> None:
        for sig, previous in self._previous.items():
            signal.signal(sig, signal.SIG_DFL if self._final else previous)
        self._previous.clear()
        _ACTIVE.remove(self)


_ACTIVE: list[InterruptHandlers] = []


def interrupt_requested() -> str | None:
    """Name the SIGINT or SIGTERM that came while :class:`InterruptHandlers` are installed.

    Returns
    -------
    str or None
        ``"SIGINT"`` or ``"SIGTERM"``; None when none came (or none are installed).
    """
    for h in _ACTIVE:
        if h.signum is not None:
            return signal.Signals(h.signum).name
    return None
