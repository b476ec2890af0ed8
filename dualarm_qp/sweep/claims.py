"""The sweep folder's store of finished points, shared by sweeps run into one folder.

Two sweeps started on one folder (or one started while another still runs) compute
every point once, the way two benches on one folder do (:mod:`dualarm_qp.bench.store`,
whose files and functions this uses)::

    points.jsonl      one JSON line per finished point (its "key" field names the point)
    .lock             flock'ed while the store is read or appended to
    .claims/<key>     flock'ed by the sweep computing that point

A sweep *claims* a point (an exclusive flock of ``.claims/<key>``, never waited for)
just before it sends it to be computed, then reads what the store gained since it last
looked: a point stored meanwhile by another sweep is taken from there, not computed. A
point claimed by another sweep is left to it and looked at again later; the kernel
releases a claim when its owner exits, however it exits, so a point whose sweep was
interrupted or killed is computed by the one still running. A point's record is appended
and its claim file removed, in that order, once it is computed.

Only the points under way are claimed (one open file each): :data:`MAX_CLAIMS` at most,
or half the process's limit of open files if that is lower.
"""

from __future__ import annotations

import json
import os
import resource
from pathlib import Path
from typing import Any

from ..bench.store import Claim, append_result, claim_job, locked

STORE_FILE = "points.jsonl"

#: Most points one sweep claims at a time (one open file each).
MAX_CLAIMS = 4096


def claims_cap() -> int:
    """Return the most points to claim at a time: :data:`MAX_CLAIMS`, fewer if files are few."""
    try:
        soft, _ = resource.getrlimit(resource.RLIMIT_NOFILE)
    except (OSError, ValueError):
        return 256
    if soft == resource.RLIM_INFINITY:
        return MAX_CLAIMS
    return max(16, min(MAX_CLAIMS, soft // 2))


class PointStore:
    """The store of one sweep folder: records read as the file grows, claims held.

    Parameters
    ----------
    folder : Path
        The sweep folder (created if missing).

    Attributes
    ----------
    path : Path
        The store file (``points.jsonl``).
    """

    def __init__(self, folder: Path) -> None:
        self.folder = folder
        self.path = folder / STORE_FILE
        self._offset = 0
        self._claims: dict[str, Claim] = {}

    @property
    def held(self) -> int:
        """Points claimed by this sweep now."""
        return len(self._claims)

    def read_new(self) -> dict[str, dict[str, Any]]:
        """Return the records appended since the last call (all of them the first time).

        Reads under the store's lock, up to the last whole line (a line torn by a
        killed writer is cut by the next append, see :mod:`dualarm_qp.bench.store`).
        """
        if not self.path.exists():
            return {}
        with locked(self.folder):
            with open(self.path, "rb") as fh:
                size = os.fstat(fh.fileno()).st_size
                if size < self._offset:  # the file was replaced: read it all again
                    self._offset = 0
                fh.seek(self._offset)
                data = fh.read(size - self._offset)
        whole = data[:data.rfind(b"\n") + 1]
        self._offset += len(whole)
        out: dict[str, dict[str, Any]] = {}
        for raw in whole.splitlines():
            try:
                rec = json.loads(raw)
            except ValueError:
                continue
            if isinstance(rec, dict) and isinstance(rec.get("key"), str):
                out[rec["key"]] = rec
        return out

    def claim(self, key: str) -> bool:
        """Claim point ``key``; False when another sweep holds it (nothing waits)."""
        if key in self._claims:
            return True
        claim = claim_job(self.folder, key, wait=False)
        if claim is None:
            return False
        self._claims[key] = claim
        return True

    def store(self, record: dict[str, Any]) -> None:
        """Append a finished point's record, then give its claim up (its file removed)."""
        append_result(self.path, record)
        claim = self._claims.pop(record["key"], None)
        if claim is not None:
            claim.release(stored=True)

    def release(self, key: str, *, stored: bool = False) -> None:
        """Give the claim on ``key`` up (its file removed when ``stored``)."""
        claim = self._claims.pop(key, None)
        if claim is not None:
            claim.release(stored=stored)

    def release_all(self) -> None:
        """Give every claim up; the points stay to be computed (their files stay)."""
        for key in list(self._claims):
            self.release(key)
