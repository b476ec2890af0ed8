"""A signal that comes while a SignalHold puts the previous handlers back is held too.

The hold puts back SIGINT's handler, then SIGTERM's. A SIGINT that came in between
reached the handler already put back, which raised out of the hold's exit (even with
``deliver=False``), and left SIGTERM's handler the hold's own: a later ``kill`` was
swallowed for good. The signal is sent here from inside the putting back, at exactly
that point, so that the test does not depend on timing.
"""

from __future__ import annotations

import os
import signal

import pytest

from dualarm_qp import _signals
from dualarm_qp._signals import Interrupted, InterruptHandlers, SignalHold

pytestmark = [pytest.mark.skipif(os.name != "posix", reason="POSIX signals"),
              pytest.mark.sigint]


def _signal_after_first_put_back(monkeypatch: pytest.MonkeyPatch, signum: int) -> list[int]:
    """Make the first handler put back (of ``signum``) send ``signum`` to this process."""
    real = signal.signal
    sent: list[int] = []

    def put_back(sig: int, handler: object) -> object:
        old = real(sig, handler)  # type: ignore[arg-type]
        if sig == signum and not sent and isinstance(handler, InterruptHandlers):
            sent.append(sig)
            os.kill(os.getpid(), sig)  # its handler runs at the next bytecode: here
        return old

    monkeypatch.setattr(_signals.signal, "signal", put_back)
    return sent


def test_a_signal_while_the_handlers_come_back_is_held(monkeypatch: pytest.MonkeyPatch
                                                        ) -> None:
    """deliver=False: nothing comes out of the block; the signal waits for deliver()."""
    with InterruptHandlers() as handlers:
        hold = SignalHold(deliver=False)
        try:
            with hold:
                sent = _signal_after_first_put_back(monkeypatch, signal.SIGINT)
        except KeyboardInterrupt:
            pytest.fail("the signal came out of the hold's exit")
        finally:
            monkeypatch.undo()
            signal.signal(signal.SIGTERM, handlers)  # whatever the hold left, for the rest
        assert sent == [signal.SIGINT]
        assert hold.signum == signal.SIGINT
        assert signal.getsignal(signal.SIGINT) is handlers
        assert signal.getsignal(signal.SIGTERM) is handlers  # not the hold's, for good
        with pytest.raises(Interrupted):
            hold.deliver()
    assert handlers.signum == signal.SIGINT


def test_a_signal_while_the_handlers_come_back_is_delivered_once_they_are(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """deliver=True: the signal comes out of the block once every handler is back."""
    with InterruptHandlers() as handlers:
        with pytest.raises(Interrupted), SignalHold():
            _signal_after_first_put_back(monkeypatch, signal.SIGINT)
        monkeypatch.undo()
        left = signal.getsignal(signal.SIGTERM)
        signal.signal(signal.SIGTERM, handlers)  # whatever the hold left, for the rest
        assert left is handlers
        assert signal.getsignal(signal.SIGINT) is handlers
