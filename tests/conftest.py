"""Shared test set-up: this folder is on ``sys.path``, so every test imports the one
independent DH oracle (``dh_oracle``) the same way.

Tests marked ``@pytest.mark.sigint`` send or simulate SIGINT: they run with Python's
own SIGINT handler installed, whatever SIGINT state pytest inherited (see ``sigint.py``).
"""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from sigint import python_sigint


@pytest.fixture(autouse=True)
def _sigint_state(request: pytest.FixtureRequest) -> Iterator[None]:
    """Python's SIGINT handler for a ``sigint`` test; nothing changed for the others."""
    if request.node.get_closest_marker("sigint") is None:
        yield
        return
    with python_sigint():
        yield
