"""Append-only result store: one JSON line per finished job, so a bench can resume.

Each line is written with a single ``write`` on a file opened for appending and then
flushed to disk, so an interrupted bench leaves either a whole line or, at worst, a torn
last line without its newline. :func:`load_results` drops such a torn line (and cuts it
from the file) so that the next append starts on a fresh line.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

from .._io import jsonable


def append_result(path: Path, record: dict[str, Any]) -> None:
    """Append ``record`` as one JSON line to ``path`` (created if missing)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    line = (json.dumps(jsonable(record), separators=(",", ":")) + "\n").encode("utf-8")
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o644)
    try:
        os.write(fd, line)
        os.fsync(fd)
    finally:
        os.close(fd)


def load_results(path: Path) -> dict[str, dict[str, Any]]:
    """Finished jobs stored in ``path``, by their ``"key"`` field (later lines win).

    A last line without its newline (a write cut short) is ignored and removed from the
    file; a line that is not valid JSON is ignored.
    """
    if not path.exists():
        return {}
    data = path.read_bytes()
    if data and not data.endswith(b"\n"):
        cut = data.rfind(b"\n") + 1
        data = data[:cut]
        tmp = path.with_name(f".{path.name}.tmp")
        tmp.write_bytes(data)
        os.replace(tmp, path)
    out: dict[str, dict[str, Any]] = {}
    for raw in data.splitlines():
        try:
            rec = json.loads(raw)
        except ValueError:
            continue
        if isinstance(rec, dict) and isinstance(rec.get("key"), str):
            out[rec["key"]] = rec
    return out
