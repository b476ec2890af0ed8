"""Registry of step solvers, by name.

A solver module registers itself with one call to :func:`register`; importing
:mod:`dualarm_qp.solvers` imports every solver module. Unavailable solvers (a backend
that is not installed) stay listed, with the pip extra that installs them.
"""

from __future__ import annotations

import inspect
import math
from collections.abc import Callable, Iterable
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


class SolverOptionError(InvalidInputError):
    """A solver option with an unknown name, a wrong type or a value out of range.

    Attributes
    ----------
    solver : str
        Registry name of the solver.
    option : str
        The offending option.
    valid : tuple of str
        The option names the solver accepts (for an unknown name), else empty.
    """

    def __init__(self, solver: str, option: str, message: str, *,
                 valid: Iterable[str] = ()) -> None:
        self.solver = solver
        self.option = option
        self.valid = tuple(valid)
        self.reason = message
        text = f"solver '{solver}' option '{option}': {message}"
        if self.valid:
            text += f" (valid: {', '.join(self.valid)})"
        super().__init__(text)


def check_number(solver: str, option: str, value: Any, *, integer: bool = False,
                 minimum: float | None = None, strict: bool = False) -> None:
    """Check one numeric option of a solver (the constructors' shared check).

    Parameters
    ----------
    solver, option : str
        Names for the message.
    value : object
        The value given.
    integer : bool
        Require an integer.
    minimum : float, optional
        Lower bound.
    strict : bool
        The bound is exclusive (``value > minimum``).

    Raises
    ------
    SolverOptionError
        A boolean, a non-number, NaN or infinity, a non-integer where one is needed,
        or a value below the bound.
    """
    kind = "an integer" if integer else "a number"
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise SolverOptionError(solver, option, f"expected {kind}, got {value!r}")
    if integer and not isinstance(value, int):
        raise SolverOptionError(solver, option, f"expected {kind}, got {value!r}")
    if not math.isfinite(value):
        raise SolverOptionError(solver, option, f"expected a finite number, got {value!r}")
    if minimum is not None and (value <= minimum if strict else value < minimum):
        rel = ">" if strict else ">="
        raise SolverOptionError(solver, option, f"must be {rel} {minimum:g}, got {value!r}")


def check_tolerance(solver: str, value: Any) -> None:
    """Check a solver's ``tol`` argument (a :class:`~.base.Tolerance`).

    Raises
    ------
    SolverOptionError
        ``value`` is not a Tolerance (a file cannot give one).
    """
    from .base import Tolerance

    if not isinstance(value, Tolerance):
        raise SolverOptionError(solver, "tol", f"expected a Tolerance object, got {value!r}")


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


def canonical_name(name: str) -> str:
    """Registry name of ``name`` (an alias such as ``qp:proxqp`` gives ``qp:proxsuite``)."""
    return _ALIASES.get(name, name)


def option_names(name: str) -> list[str] | None:
    """Keyword options of a solver whose factory lists them, or None if it takes any."""
    info = solver_info(name)
    try:
        params = inspect.signature(info.factory).parameters.values()
    except (TypeError, ValueError):
        return None
    if any(p.kind is inspect.Parameter.VAR_KEYWORD for p in params):
        return None
    return [p.name for p in params if not p.name.startswith("_")
            and p.kind in (inspect.Parameter.KEYWORD_ONLY,
                           inspect.Parameter.POSITIONAL_OR_KEYWORD)]


def get_solver(name: str, **options: Any) -> StepSolver:
    """Build the solver registered as ``name`` with keyword ``options``.

    Raises
    ------
    SolverNotFoundError
        See :func:`solver_info`.
    SolverOptionError
        An option the solver does not know (the message lists the valid names), or a
        value of the wrong type or out of range.
    InvalidInputError
        Another refusal of the options by the solver.
    """
    info = solver_info(name)
    valid = option_names(name)
    if valid is not None:
        for key in options:
            if key not in valid:
                raise SolverOptionError(info.name, key, "unknown option",
                                        valid=valid or ["(none)"])
    try:
        return info.factory(**options)
    except TypeError as err:
        raise InvalidInputError(f"bad options for solver '{name}': {err}") from err
