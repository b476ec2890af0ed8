"""What keys a bench job: its configuration, its settings, the code; and where it ran.

A job's result is stored under a key (:func:`settings_hash`) made of the configuration
file's path and content, the solver, the settings (:class:`BenchSettings`), the record
format and a digest of the package's source code (:func:`code_digest`): a bench run into
the same folder reuses exactly the jobs whose key is stored.
"""

from __future__ import annotations

import functools
import hashlib
import json
import math
import os
import platform
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .. import __version__
from ..errors import InvalidInputError
from ..experiments.config import load_config
from ..experiments.options import options_for
from ..solvers.base import DEFAULT_TOLERANCE, Tolerance
from ..solvers.registry import solver_info

#: Bumped when a job's record changes meaning, so stale stored results are not reused.
RECORD_FORMAT = 1


@functools.lru_cache(maxsize=1)
def code_digest() -> str:
    """Digest of the package's Python source: sha256 over sorted relative paths + contents.

    Computed once per process; part of every job's key, so that stored results of other
    code are not reused.
    """
    root = Path(__file__).resolve().parents[1]
    h = hashlib.sha256()
    for path in sorted(root.rglob("*.py"), key=lambda p: p.relative_to(root).as_posix()):
        h.update(path.relative_to(root).as_posix().encode() + b"\0")
        h.update(path.read_bytes() + b"\0")
    return h.hexdigest()


@dataclass(frozen=True)
class BenchSettings:
    """Settings that change a job's numbers (they are part of its key).

    Parameters
    ----------
    repeat : int
        Rollouts per job; their step timings are pooled.
    duration : float, optional
        Override of every configuration's run length [s] (None: as configured).
    tolerance : Tolerance
        What counts as meeting the equality and the bounds.
    replay : bool
        Replay the canonical steps (objective gap, bare backend time).
    solver_options : dict
        Options per solver name (``--solver-option``), applied over a configuration's
        own options when that solver runs; part of that solver's job keys only.
    """

    repeat: int = 1
    duration: float | None = None
    tolerance: Tolerance = DEFAULT_TOLERANCE
    replay: bool = True
    solver_options: dict[str, dict[str, Any]] = field(default_factory=dict, hash=False)

    def __post_init__(self) -> None:
        if not (isinstance(self.repeat, int) and self.repeat >= 1):
            raise InvalidInputError(f"repeat must be an integer >= 1, got {self.repeat!r}")
        if self.duration is not None and not (math.isfinite(self.duration)
                                              and self.duration > 0):
            raise InvalidInputError(f"duration must be a positive number of seconds, got "
                                    f"{self.duration}")

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready form (what the key hashes)."""
        return {"repeat": self.repeat, "duration_s": self.duration,
                "tol_equality": self.tolerance.equality, "tol_bounds": self.tolerance.bounds,
                "replay": self.replay}


@dataclass(frozen=True)
class BenchConfig:
    """A configuration file read once: its path, text hash and built experiment."""

    path: str
    name: str
    sha256: str


def settings_hash(config: BenchConfig, solver: str, settings: BenchSettings) -> str:
    """Key of one job: hash of the configuration text, solver, settings, format and code."""
    key = {"config": config.path, "config_sha256": config.sha256,
           "solver": solver, "settings": settings.as_dict(),
           "format": RECORD_FORMAT, "version": __version__,
           "code": code_digest()}
    options = options_for(solver, settings.solver_options)
    if options:  # only this solver's command-line options
        key["solver_options"] = options
    blob = json.dumps(key, sort_keys=True)
    return hashlib.sha256(blob.encode()).hexdigest()[:16]


def read_config(path: str | Path) -> BenchConfig:
    """Validate a configuration file (raises ConfigError, exit code 2 in the CLI)."""
    p = Path(path)
    cfg = load_config(p)
    return BenchConfig(str(path), cfg.name, hashlib.sha256(p.read_bytes()).hexdigest())


def check_solvers(names: Sequence[str]) -> list[str]:
    """Return ``names`` after checking each is registered and installed.

    Raises
    ------
    SolverNotFoundError
        Naming the pip extra for a known solver whose backend is missing.
    """
    if not names:
        from ..solvers import available_solvers

        raise InvalidInputError("no solver given; available solvers: "
                                + ", ".join(available_solvers()))
    for name in names:
        solver_info(name)
    return list(dict.fromkeys(names))


def machine_info() -> dict[str, Any]:
    """Describe the machine and its load, for the report."""
    cpu = platform.processor() or ""
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as fh:
            for line in fh:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    try:
        load = list(os.getloadavg())
    except OSError:
        load = []
    import qpsolvers

    return {"cpu": cpu, "cpus": os.cpu_count(), "system": platform.platform(),
            "python": platform.python_version(), "numpy": np.__version__,
            "qpsolvers": qpsolvers.__version__, "dualarm_qp": __version__,
            "load_average": load, "time": time.strftime("%Y-%m-%d %H:%M:%S %z")}


__all__ = ["RECORD_FORMAT", "BenchConfig", "BenchSettings", "check_solvers", "code_digest",
           "machine_info", "read_config", "settings_hash"]
