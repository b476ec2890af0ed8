"""A signal held while a cell runs does not break a library's blocking read.

libfranka reads a robot's state with a blocking system call; a SIGTERM that came during
it, interrupting the call, made the read fail ("Net Exception") and the drive stop on a
cell error instead of being stopped by the signal. Under :class:`SignalHold` the call
goes on (``SA_RESTART``), and the signal is acted on once the sample is done.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import os
import signal
import threading
import time

import pytest

from dualarm_qp._signals import SignalHold

libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6", use_errno=True)


def _read_through_a_signal() -> tuple[int, int]:
    """A C-level read() of a pipe, sent SIGTERM while it waits, then fed a byte."""
    r, w = os.pipe()
    main = threading.get_ident()

    def poke() -> None:
        time.sleep(0.2)
        signal.pthread_kill(main, signal.SIGTERM)
        time.sleep(0.2)
        os.write(w, b"x")

    thread = threading.Thread(target=poke)
    thread.start()
    buf = ctypes.create_string_buffer(1)
    try:
        got = libc.read(r, buf, 1)
        return got, ctypes.get_errno()
    finally:
        thread.join()
        os.close(r)
        os.close(w)


@pytest.mark.skipif(threading.current_thread() is not threading.main_thread(),
                    reason="signal handlers are set in the main thread only")
@pytest.mark.slow
def test_a_held_signal_lets_a_blocking_read_finish() -> None:
    with SignalHold(deliver=False) as hold:
        first = _read_through_a_signal()
        with SignalHold(deliver=False):  # a nested hold keeps it so
            pass
        second = _read_through_a_signal()
        held, hold.signum = hold.signum, None  # the test's own signal: not passed on
    assert held == signal.SIGTERM
    assert first[0] == 1, f"the read was interrupted (errno {first[1]})"
    assert second[0] == 1, f"after a nested hold, the read was interrupted (errno {second[1]})"
