"""Fitted capsules kept on disk, so that a robot's capsules are fitted once per machine.

Fitting the capsules of a URDF arm (:func:`~dualarm_qp.geometry.fit.fit_capsule` for
each joint) takes about a second for a 7-joint arm, most of it SciPy's optimiser and its
import. Every process that builds the arm needs the same capsules: each ``dualarm-qp
run``, each worker of a sweep. :func:`cached_fit` keeps them in a folder:

* the key is a SHA-256 digest of what the fit reads (every ball's centre and radius, in
  the order given, the key of each capsule) and of what decides how it fits (the source
  of :mod:`~dualarm_qp.geometry.fit`, SciPy's version): a changed mesh, scale or
  placement in the robot description, or a changed fit, gives another key, so a file
  is never stale;
* the folder is ``$DUALARM_QP_CACHE`` when set, else ``$XDG_CACHE_HOME/dualarm_qp``, else
  ``~/.cache/dualarm_qp``; the capsules go in its ``capsules/`` subfolder, one JSON file
  per key, written atomically (a temporary file renamed into place), so processes
  fitting the same arm at once each write a whole file and a reader sees one whole
  file or none;
* a file that cannot be read or does not hold the capsules expected (cut short, edited,
  from another version) is ignored and replaced; a folder that cannot be written (a
  read-only home) only means the fit is not kept.

Floats are written by ``repr``, which reads back to the same bits: capsules from the
folder equal the fitted ones exactly.
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Mapping, Sequence
from importlib import metadata
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from .._io import write_text
from ..errors import DualArmError
from . import fit
from .shapes import Capsule

FloatArray = NDArray[np.float64]
#: Balls of one capsule: centres (m, 3) [m] and radii (m,) [m].
Balls = tuple[FloatArray, FloatArray]

#: The environment variable naming the cache folder.
CACHE_ENV = "DUALARM_QP_CACHE"


def cache_dir() -> Path:
    """Return the cache folder: ``$DUALARM_QP_CACHE``, else the user's cache folder.

    The user's cache folder is ``$XDG_CACHE_HOME/dualarm_qp`` when ``XDG_CACHE_HOME``
    is set (and not empty), else ``~/.cache/dualarm_qp``. Nothing is created here.
    """
    chosen = os.environ.get(CACHE_ENV)
    if chosen:
        return Path(chosen).expanduser()
    xdg = os.environ.get("XDG_CACHE_HOME")
    return (Path(xdg).expanduser() if xdg else Path.home() / ".cache") / "dualarm_qp"


def _fit_identity() -> bytes:
    """Return what decides how the capsules are fitted: the fit's source, SciPy's version.

    Raises
    ------
    OSError
        The fit's source cannot be read (then nothing is cached).
    """
    try:
        scipy = metadata.version("scipy")
    except metadata.PackageNotFoundError:  # pragma: no cover - scipy is a dependency
        scipy = "none"
    return Path(fit.__file__).read_bytes() + f"scipy {scipy}".encode()


def balls_digest(balls: Mapping[int, Sequence[Balls]]) -> str:
    """Return the key of a set of capsules: a SHA-256 hex digest of the fit's input.

    Parameters
    ----------
    balls : mapping of int to sequence of (centres, radii)
        For each capsule key, the balls it must contain (centres (m, 3) [m], radii
        (m,) [m]), as :func:`cached_fit` takes them.

    Raises
    ------
    OSError
        The fit's source cannot be read.
    """
    h = hashlib.sha256(_fit_identity())
    for key in sorted(balls):
        h.update(f"|key {key}|".encode())
        for centres, radii in balls[key]:
            c = np.ascontiguousarray(centres, dtype="<f8")
            r = np.ascontiguousarray(radii, dtype="<f8")
            h.update(f"{c.shape}{r.shape}".encode())
            h.update(c.tobytes())
            h.update(r.tobytes())
    return h.hexdigest()


def _path(digest: str) -> Path:
    return cache_dir() / "capsules" / f"{digest}.json"


def _load(path: Path, keys: Sequence[int]) -> dict[int, Capsule] | None:
    """Read the capsules of ``keys`` from ``path``; None when missing or unusable."""
    try:
        stored = json.loads(path.read_text(encoding="utf-8"))["capsules"]
        if not isinstance(stored, dict) or sorted(stored) != sorted(str(k) for k in keys):
            return None
        return {key: Capsule(np.array(stored[str(key)]["a"], dtype=np.float64),
                             np.array(stored[str(key)]["b"], dtype=np.float64),
                             float(stored[str(key)]["radius"]))
                for key in keys}
    except (OSError, ValueError, KeyError, TypeError, DualArmError):
        return None


def _store(path: Path, capsules: Mapping[int, Capsule]) -> None:
    """Write ``capsules`` to ``path`` atomically; a folder that cannot be written is left."""
    text = json.dumps({"capsules": {str(key): {"a": cap.a.tolist(), "b": cap.b.tolist(),
                                               "radius": cap.radius}
                                    for key, cap in capsules.items()}})
    try:
        write_text(path, text)
    except OSError:
        pass


def cached_fit(balls: Mapping[int, Sequence[Balls]]) -> dict[int, Capsule]:
    """Return one capsule per key containing its balls: from the cache, or fitted and kept.

    Parameters
    ----------
    balls : mapping of int to sequence of (centres, radii)
        For each key, the balls its capsule must contain (at least one ball in all).

    Returns
    -------
    dict of int to Capsule
        ``fit_capsule`` of each key's balls stacked, in key order; equal, bit for bit,
        to what the fit gives.
    """
    keys = sorted(balls)
    try:
        path: Path | None = _path(balls_digest(balls))
    except (OSError, RuntimeError):  # no fit source to key on, no home folder
        path = None
    found = None if path is None else _load(path, keys)
    if found is not None:
        return found
    fitted = {key: fit.fit_capsule(np.vstack([c for c, _ in balls[key]]),
                               np.concatenate([r for _, r in balls[key]]))
              for key in keys}
    if path is not None:
        _store(path, fitted)
    return fitted


__all__ = ["CACHE_ENV", "balls_digest", "cache_dir", "cached_fit"]
