"""The compiled kernel ``dualarm_qp._kernel``, checked on import (private).

The exact solver, the factorisations every solver shares and the certificate's numeric
core are C++ (``src/kernel``, built by ``pip install``). This module imports the
extension once and refuses it, with a :class:`~dualarm_qp.errors.KernelError` that says
what to do, when it is missing or was built from other sources than those next to the
package (an editable install whose C++ was edited since the last build).
"""

from __future__ import annotations

import hashlib
from pathlib import Path

from .errors import KernelError

#: What to run when the kernel is missing or stale.
REBUILD = "run `pip install -e .` (or `pip install .`) in the project folder again"

#: The kernel's sources, when the package runs from a source tree.
SOURCES = Path(__file__).resolve().parents[1] / "src" / "kernel"

try:
    from . import _kernel as kernel
except ImportError as err:  # pragma: no cover - depends on the installation
    raise KernelError(
        f"the compiled kernel dualarm_qp._kernel cannot be imported ({err}); "
        f"it is built when the package is installed: {REBUILD}") from err


def source_hash(folder: Path = SOURCES) -> str | None:
    """SHA-256 of the kernel's sources as CMakeLists.txt computes it, or None without them.

    The ``.cpp`` and ``.hpp`` files, sorted by path, each read as lower-case hex text,
    concatenated.
    """
    files = sorted([*folder.glob("*.cpp"), *folder.glob("*.hpp")], key=str)
    if not files:
        return None
    text = "".join(f.read_bytes().hex() for f in files)
    return hashlib.sha256(text.encode("ascii")).hexdigest()


def check_fresh(folder: Path = SOURCES, built: str = kernel.SOURCE_HASH) -> None:
    """Raise :class:`KernelError` if the kernel was built from other sources than ``folder``'s.

    An installed wheel has no sources next to it: nothing to compare, nothing raised.
    """
    expected = source_hash(folder)
    if expected is not None and expected != built:
        raise KernelError(
            f"the compiled kernel dualarm_qp._kernel is stale: it was built from other "
            f"sources than those in {folder}; {REBUILD}")


check_fresh()

__all__ = ["KernelError", "check_fresh", "kernel", "source_hash"]
