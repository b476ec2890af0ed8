"""Registry of step solvers, by name.

A solver module registers itself with one call to :func:`register`; importing
:mod:`dualarm_qp.solvers` imports every solver module. Unavailable solvers (a backend
that is not installed) stay listed, with the pip extra that installs them.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from ..errors import InvalidInputError, SolverNotFoundError
from .base import StepSolver


@dataclass(frozen=True)
class SolverInfo:
    """One registry entry.

    Attributes
    ----------
    name : str
        Registry name, e.g. ``"nullspace"`` or ``"qp:osqp"``.
    description : str
        One line for ``dualarm-qp solvers``.
    available : bool
        Whether the solver can run on this machine.
    extra : str or None
        The pip extra of dualarm-qp that installs what the solver needs.
    hard_bounds : bool
        Whether the solver guarantees the bounds (False for the paper's reference step).
    """

    name: str
    description: str
    available: bool
    extra: str | None
    hard_bounds: bool
    factory: Callable[..., StepSolver]


_REGISTRY: dict[str, SolverInfo] = {}
_ALIASES: dict[str, str] = {}


def register(
    name: str,
    factory: Callable[..., StepSolver],
    *,
    description: str,
    available: bool = True,
    extra: str | None = None,
    hard_bounds: bool = True,
    aliases: tuple[str, ...] = (),
) -> None:
    """Add a solver to the registry (one line per solver module).

    ``aliases`` are other names :func:`get_solver` accepts for it (e.g. ``"qp:proxqp"``
    for ``"qp:proxsuite"``); they are not listed separately.
    """
    _REGISTRY[name] = SolverInfo(name, description, available, extra, hard_bounds, factory)
    for alias in aliases:
        _ALIASES[alias] = name


def list_solvers() -> list[SolverInfo]:
    """Every registered solver, available or not, in registration order."""
    return list(_REGISTRY.values())


def available_solvers() -> list[str]:
    """Names of the solvers that can run here."""
    return [info.name for info in _REGISTRY.values() if info.available]


def solver_info(name: str) -> SolverInfo:
    """Registry entry of ``name``.

    Raises
    ------
    SolverNotFoundError
        Unknown name, or a solver whose backend is not installed (the message names
        the pip extra).
    """
    info = _REGISTRY.get(name) or _REGISTRY.get(_ALIASES.get(name, ""))
    if info is None:
        raise SolverNotFoundError(name, available=available_solvers())
    if not info.available:
        raise SolverNotFoundError(
            name, available=available_solvers(), extra=info.extra, known=True
        )
    return info


def get_solver(name: str, **options: Any) -> StepSolver:
    """Build the solver registered as ``name`` with keyword ``options``.

    Raises
    ------
    SolverNotFoundError
        See :func:`solver_info`.
    InvalidInputError
        An option the solver does not accept.
    """
    info = solver_info(name)
    try:
        return info.factory(**options)
    except TypeError as err:
        raise InvalidInputError(f"bad options for solver '{name}': {err}") from err
