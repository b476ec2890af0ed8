"""Turning SIGINT (Ctrl-C) and SIGTERM (``kill``) into an orderly stop.

Every command (``run``, ``reproduce``, ``bench``) uses the same two pieces:

* :class:`InterruptHandlers`: both signals raise :class:`Interrupted` (a
  KeyboardInterrupt) and are recorded, so that an interrupt that some code swallowed
  (a KeyboardInterrupt raised inside a weak-reference callback, turned into an
  ImportError by an extension module, or caught inside a bench job) still stops the
  command: :func:`interrupt_requested`, :func:`raise_if_interrupted`. The command line
  installs them for the whole command; a bench installs them again so that it also
  stops cleanly when called as a library. They nest: the outer ones record too.
* :class:`SignalHold`: both signals are held while a block that must not be cut short
  runs (a set of output files, a finished bench job being stored) and passed on to the
  handler in place once it ends.

A signal that the process inherited as *ignored* stays ignored (SIGINT in a background
job of a non-interactive shell); outside the main thread nothing is installed. A
backend with its own SIGINT handler (osqp) swallows a Ctrl-C during a solve:
:func:`pass_on_sigint` hands it back.
"""

from __future__ import annotations

import signal
import threading
from types import FrameType
from typing import Any

#: The signals that stop a command: Ctrl-C, and ``kill``'s default.
STOP_SIGNALS: tuple[signal.Signals, ...] = (signal.SIGINT, signal.SIGTERM)


def signal_name(signum: int | None) -> str:
    """``"SIGINT"``, ``"SIGTERM"``, ... (``"interrupt"`` when unknown)."""
    if signum is None:
        return "interrupt"
    try:
        return signal.Signals(signum).name
    except ValueError:
        return f"signal {signum}"


class Interrupted(KeyboardInterrupt):
    """A stop signal (SIGINT or SIGTERM) came; its text is the signal's name.

    Parameters
    ----------
    signum : int or None
        The signal (None when not known, e.g. a plain KeyboardInterrupt re-raised).
    """

    def __init__(self, signum: int | None = None) -> None:
        super().__init__(signal_name(signum))
        self.signum = signum


def pass_on_sigint() -> None:
    """Hand a SIGINT that a backend's own handler swallowed to the process's handler.

    With Python's default handler or :class:`InterruptHandlers` this raises; a process
    that ignores SIGINT goes on.
    """
    signal.raise_signal(signal.SIGINT)


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


class InterruptHandlers:
    """Make SIGINT and SIGTERM raise :class:`Interrupted`, and remember that they came.

    Use as a context manager; the previous handlers come back on exit. Installed inside
    other InterruptHandlers, a signal is recorded in those too (so that
    :func:`interrupt_requested` sees it whichever are innermost).

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

    def _record(self, signum: int) -> None:
        if self.signum is None:
            self.signum = signum
        outer = self._previous.get(signal.Signals(signum))
        if isinstance(outer, InterruptHandlers):
            outer._record(signum)

    def __call__(self, signum: int, frame: FrameType | None) -> None:
        self._record(signum)
        raise Interrupted(signum)

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


def _restore(previous: list[tuple[signal.Signals, Any]]) -> None:
    """Install the handlers of ``previous`` again (an outer hold's: without SA_RESTART off)."""
    for sig, handler in previous:
        signal.signal(sig, handler)
        if isinstance(getattr(handler, "__self__", None), SignalHold):  # an outer hold
            signal.siginterrupt(sig, False)


def _requested() -> int | None:
    for h in _ACTIVE:
        if h.signum is not None:
            return h.signum
    return None


def interrupt_requested() -> str | None:
    """Name the SIGINT or SIGTERM that came while :class:`InterruptHandlers` are installed.

    Returns
    -------
    str or None
        ``"SIGINT"`` or ``"SIGTERM"``; None when none came (or none are installed).
    """
    signum = _requested()
    return None if signum is None else signal_name(signum)


def raise_if_interrupted() -> None:
    """Raise :class:`Interrupted` if a stop signal came, even if it was swallowed."""
    signum = _requested()
    if signum is not None:
        raise Interrupted(signum)


class SignalHold:
    """Hold SIGINT and SIGTERM while a block runs, so that they cannot cut it short.

    Use as a context manager around what must be done whole (writing a set of files,
    storing a finished job): a signal received inside the block is remembered and
    passed on, once the block ends, to the handler that was in place before (with
    :class:`InterruptHandlers`: :class:`Interrupted`, recorded; with Python's default
    handler: KeyboardInterrupt; with the default action of SIGTERM: the process ends,
    its files complete). Holds nest. Outside the main thread, or for a signal the
    process ignores, nothing changes. A held signal does not interrupt a system call
    either: a library's blocking read (a robot's state) goes on (``SA_RESTART``).

    Parameters
    ----------
    deliver : bool
        Pass a held signal on when the block ends (default); with False the caller
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
        for sig in self._previous:  # a held signal lets a library's system call go on
            signal.siginterrupt(sig, False)
        return self

    def __exit__(self, exc_type: type[BaseException] | None, *exc: object) -> None:
        self._put_back()
        if self._deliver_on_exit or exc_type is not None:
            self.deliver()

    def _put_back(self) -> None:
        """Put the previous handlers back; a signal that comes half-way is held too.

        The handlers come back one signal after the other: a signal that reaches one
        already put back (which raises) before the others are would leave them held
        for good, a later ``kill`` swallowed. It is caught, held like the others, and
        every handler is put back.
        """
        previous = list(self._previous.items())
        self._previous.clear()
        try:
            _restore(previous)
        except KeyboardInterrupt as stop:  # Interrupted, or Python's default SIGINT
            if self.signum is None:
                self.signum = getattr(stop, "signum", None) or signal.SIGINT
            _restore(previous)

    def deliver(self) -> None:
        """Pass the held signal, if any, to the process's handler (it may raise)."""
        signum, self.signum = self.signum, None
        if signum is not None:
            signal.raise_signal(signum)
