"""Atomic file output and JSON conversion, shared by the experiment and bench writers.

Every output file is written to a temporary name in its folder and renamed into place,
so a run that fails or is interrupted never leaves a half-written file: a reader sees
either the previous complete file or the new complete one.

A *set* of files (a run's outputs) is written inside a
:class:`~dualarm_qp._signals.SignalHold`, so that SIGINT and SIGTERM cannot cut it short.
"""

from __future__ import annotations

import json
import math
import os
import tempfile
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import IO, Any

import numpy as np

from ._signals import SignalHold


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
