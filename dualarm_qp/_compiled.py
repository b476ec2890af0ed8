"""The compiled kernel ``dualarm_qp._kernel``, checked on import (private).

The exact solver, the factorisations every solver shares, the certificate's numeric
core and the arms' kinematics are C++ (``src/kernel``, built by ``pip install``). This
module imports the extension once and refuses it, with a
:class:`~dualarm_qp.errors.KernelError` that says what to do, when it is missing or was
built from other sources than those next to the package (an editable install whose C++
was edited since the last build). :func:`check_pinocchio` refuses an installed
Pinocchio of another release than the kernel's, :func:`check_coal` a coal of another
release.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

from .errors import KernelError

#: What to run when the kernel is missing or stale.
REBUILD = ("run `pip install --no-build-isolation -e .` (after `pip install -r "
           "requirements-build.txt`; or `pip install .`) in the project folder again")

#: The kernel's sources, when the package runs from a source tree.
SOURCES = Path(__file__).resolve().parents[1] / "src" / "kernel"

# The kernel links coal's library (libcoal.so, whose name carries no version). Its
# RUNPATH names the cmeel prefix next to the package (site-packages/cmeel.prefix/lib,
# where the libcoal wheel puts it); coal's Python package loads that same library, and
# importing it first is what lets the kernel find it in any other layout (a --target
# folder, a build tree): the loader reuses a library already loaded under that name.
try:
    import coal  # type: ignore[import-untyped]
except ImportError as err:  # pragma: no cover - depends on the installation
    raise KernelError(
        f"coal, the collision library the compiled kernel links, cannot be imported "
        f"({err}); it comes with pin: install the pinned pin and coal "
        f"(`pip install -e .` installs them)") from err

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


def check_pinocchio(installed: str, built: str = kernel.PINOCCHIO_VERSION) -> None:
    """Raise :class:`KernelError` unless the installed Pinocchio is the kernel's.

    The kernel compiles Pinocchio's kinematics from the headers of the ``pin`` wheel
    present at build time, and is handed models built by the installed ``pinocchio``
    Python package; both must be the same release (``pyproject.toml`` pins it), or the
    two sides may describe or compute the models differently. ``installed`` is
    ``pinocchio.__version__``.
    """
    if installed.split("+")[0] != built:
        raise KernelError(
            f"the compiled kernel dualarm_qp._kernel was built with Pinocchio {built}, but "
            f"Pinocchio {installed} is installed; install the pinned version "
            f"(`pip install pin=={built}`) or rebuild the kernel for this one: {REBUILD}")


def check_coal(installed: str, built: str = kernel.COAL_VERSION) -> None:
    """Raise :class:`KernelError` unless the installed coal is the kernel's.

    The kernel links the coal library of the ``pin`` wheel present at build time (its
    collision scene measures the pairs with a box with it) and calls it with coal's C++
    types, whose layout may change between releases: the installed ``coal`` must be the
    same release (``pyproject.toml`` pins it). ``installed`` is ``coal.__version__``.
    """
    if installed.split("+")[0] != built:
        raise KernelError(
            f"the compiled kernel dualarm_qp._kernel was built with coal {built}, but "
            f"coal {installed} is installed; install the pinned version "
            f"(`pip install coal=={built}`) or rebuild the kernel for this one: {REBUILD}")


check_fresh()
check_coal(str(coal.__version__))

__all__ = ["KernelError", "check_coal", "check_fresh", "check_pinocchio", "kernel",
           "source_hash"]
