"""Stopping a bench cleanly on Ctrl-C (SIGINT) or SIGTERM.

A bench must never store a job that an interrupt cut short. :class:`StopGuard` installs
handlers for SIGINT and SIGTERM that *record* the signal and raise :class:`Interrupted`
(a :class:`KeyboardInterrupt`); the bench checks the record again before it stores a
job, so an interrupt that some code swallowed still keeps the job out of the store.
Inside :meth:`StopGuard.deferred` (the append of a finished job, the report) the
handlers only record the signal, and :class:`Interrupted` is raised when the block ends,
so a finished job is either stored whole or not at all.

A signal that the process inherited as *ignored* stays ignored (a background job of a
non-interactive shell ignores SIGINT). Backends with their own SIGINT handler (osqp)
swallow a Ctrl-C during a solve and return an "interrupted" status instead;
:func:`backend_interrupted` recognises such an answer and :func:`pass_on_sigint` hands
the signal back to Python's handler.
"""

from __future__ import annotations

import contextlib
import re
import signal
import threading
from collections.abc import Iterator
from types import FrameType
from typing import Any

#: The signals a bench stops on.
STOP_SIGNALS: tuple[signal.Signals, ...] = (signal.SIGINT, signal.SIGTERM)

#: Exit code of an interrupted bench (128 + SIGINT, as a shell reports Ctrl-C).
EXIT_INTERRUPTED = 130

_INTERRUPT_WORDS = re.compile(r"\binterrupt", re.IGNORECASE)


class Interrupted(KeyboardInterrupt):
    """A bench was interrupted by a signal (SIGINT or SIGTERM) or a backend saw one.

    Parameters
    ----------
    signum : int or None
        The signal received (None when it is not known, e.g. a plain Ctrl-C
        KeyboardInterrupt raised by Python's own handler).
    """

    def __init__(self, signum: int | None = None) -> None:
        super().__init__(signal_name(signum))
        self.signum = signum


class BackendInterrupted(Exception):
    """A backend reported that a signal interrupted its solve (its answer is void)."""


def signal_name(signum: int | None) -> str:
    """``"SIGINT"``, ``"SIGTERM"``, ... (``"interrupt"`` when unknown)."""
    if signum is None:
        return "interrupt"
    try:
        return signal.Signals(signum).name
    except ValueError:
        return f"signal {signum}"


def backend_interrupted(status: Any) -> bool:
    """Whether a backend status or message says that a signal interrupted the solve.

    osqp reports ``"interrupted"`` (``OSQP_SIGINT``) when its own SIGINT handler caught a
    Ctrl-C during the solve; its answer then carries no solution.
    """
    return bool(_INTERRUPT_WORDS.search(str(status)))


def pass_on_sigint() -> None:
    """Hand a SIGINT that a backend swallowed to the process's current handler.

    With Python's (or a :class:`StopGuard`'s) handler this raises; a process that
    ignores SIGINT goes on.
    """
    signal.raise_signal(signal.SIGINT)


class StopGuard:
    """Handlers for SIGINT and SIGTERM that record the signal and raise :class:`Interrupted`.

    Use as a context manager; the previous handlers are restored on exit. Outside the
    main thread (where Python cannot set handlers) it installs nothing. A signal whose
    current disposition is "ignore" (or a handler set outside Python) is left alone.
    Guards nest: a signal caught by an inner guard is recorded in the outer ones too.

    Attributes
    ----------
    signum : int or None
        The first stop signal received while installed.
    received : int
        How many stop signals were received.
    """

    def __init__(self) -> None:
        self.signum: int | None = None
        self.received = 0
        self._defer = 0
        self._previous: dict[int, Any] = {}

    @property
    def stopped(self) -> bool:
        """Whether a stop signal has been received."""
        return self.signum is not None

    def _record(self, signum: int) -> None:
        self.received += 1
        if self.signum is None:
            self.signum = signum
        outer = self._previous.get(signum)
        if isinstance(outer, _Handler):
            outer.guard._record(signum)

    def _handle(self, signum: int) -> None:
        self._record(signum)
        if self._defer == 0:
            raise Interrupted(signum)

    def check(self) -> None:
        """Raise :class:`Interrupted` if a stop signal was received (even if swallowed)."""
        if self.signum is not None:
            raise Interrupted(self.signum)

    @contextlib.contextmanager
    def deferred(self) -> Iterator[None]:
        """Let the block run to its end; raise :class:`Interrupted` after it if signalled.

        Only a signal received during the block (or an earlier one not yet raised,
        inside a nested deferred block) raises.
        """
        before = self.received
        self._defer += 1
        try:
            yield
        finally:
            self._defer -= 1
        if self._defer == 0 and self.received > before:
            raise Interrupted(self.signum)

    def __enter__(self) -> StopGuard:
        if threading.current_thread() is not threading.main_thread():
            return self
        for sig in STOP_SIGNALS:
            current = signal.getsignal(sig)
            if current is signal.SIG_IGN or current is None:
                continue
            self._previous[sig] = current
            signal.signal(sig, _Handler(self))
        return self

    def __exit__(self, *exc: object) -> None:
        for sig, previous in self._previous.items():
            signal.signal(sig, previous)
        self._previous.clear()


class _Handler:
    """The handler a :class:`StopGuard` installs (a class, so that nested guards chain)."""

    def __init__(self, guard: StopGuard) -> None:
        self.guard = guard

    def __call__(self, signum: int, frame: FrameType | None) -> None:
        self.guard._handle(signum)
