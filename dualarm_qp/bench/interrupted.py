"""A backend solve that a signal cut short: such a job's numbers are void."""

from __future__ import annotations

import re
from typing import Any

_INTERRUPT_WORDS = re.compile(r"\binterrupt", re.IGNORECASE)


class BackendInterrupted(Exception):
    """A backend reported that a signal interrupted its solve (the job's numbers are void)."""


def backend_interrupted(status: Any) -> bool:
    """Whether a backend status or message says that a signal interrupted the solve.

    osqp reports ``"interrupted"`` (``OSQP_SIGINT``) when its own SIGINT handler caught a
    Ctrl-C during the solve; its answer then carries no solution.
    """
    return bool(_INTERRUPT_WORDS.search(str(status)))


__all__ = ["BackendInterrupted", "backend_interrupted"]
