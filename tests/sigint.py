"""The SIGINT state that the interrupt tests need, whatever state pytest inherited.

A process started in the background by a non-interactive shell (``cmd &``, ``nohup``,
many CI runners) inherits SIGINT as *ignored*, and ``dualarm_qp`` rightly keeps it
ignored. A test of what Ctrl-C does must therefore set SIGINT up itself:

* in this process, :func:`python_sigint` installs Python's own handler (a SIGINT raises
  KeyboardInterrupt) for the test's duration; tests marked ``@pytest.mark.sigint`` get it
  from ``conftest.py``;
* in a child process, :func:`child_default_sigint` (a ``preexec_fn``) puts SIGINT back at
  its default action before the child starts.

``tests/test_sigint_ignored.py`` runs the ``sigint`` tests again with SIGINT ignored.
"""

from __future__ import annotations

import signal
from collections.abc import Iterator
from contextlib import contextmanager


@contextmanager
def python_sigint() -> Iterator[None]:
    """Python's default SIGINT handler inside the block; the previous one afterwards."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def child_default_sigint() -> None:
    """In a child, before ``exec``: SIGINT at its default action (ends the process)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)
