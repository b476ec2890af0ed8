"""Solver options given on the command line: ``--solver-option SOLVER.OPTION=VALUE``.

Solver names contain ``:`` but never ``.`` (``qp:osqp``), so the text before the first
``.`` is the solver and the rest up to ``=`` the option; the value is read as a YAML
scalar, as in an experiment file (``1e-9``, ``200``, ``true``, ``qdldl``). Options on the
command line belong to the solver they name and reach it only when that solver runs;
they override the file's ``solver.options`` (which belong to the file's own solver).
"""

from __future__ import annotations

from collections.abc import Collection, Iterable, Mapping
from typing import Any

from ..errors import InvalidInputError
from ..solvers.registry import SolverOptionError, canonical_name, get_solver, solver_info
from .yaml_file import yaml_scalar


class SolverFlagError(InvalidInputError):
    """A ``--solver-option`` that is malformed or that its solver refuses."""


#: Per solver (registry name), its options: ``{"qp:osqp": {"eps_abs": 1e-9}}``.
SolverOptions = Mapping[str, Mapping[str, Any]]

FLAG = "--solver-option"


def parse_solver_options(items: Iterable[str] | None) -> dict[str, dict[str, Any]]:
    """Parse ``SOLVER.OPTION=VALUE`` items into options per solver.

    Parameters
    ----------
    items : iterable of str, optional
        The flag's values, in order; a later value of the same option wins.

    Returns
    -------
    dict
        Registry name (aliases resolved: ``qp:proxqp`` is ``qp:proxsuite``) -> option
        name -> value.

    Raises
    ------
    InvalidInputError
        A malformed item (no ``.`` after the solver, no ``=``, an empty option name,
        a value that is not one YAML scalar).
    SolverNotFoundError
        An unknown or uninstalled solver.
    """
    out: dict[str, dict[str, Any]] = {}
    for item in items or ():
        lhs, eq, text = item.partition("=")
        solver, dot, option = lhs.partition(".")
        if not (eq and dot and solver.strip() and option.strip()):
            raise SolverFlagError(f"{FLAG} {item!r}: expected SOLVER.OPTION=VALUE, e.g. "
                                    f"{FLAG} qp:osqp.eps_abs=1e-9")
        option = option.strip()
        if not option.isidentifier():
            raise SolverFlagError(f"{FLAG} {item!r}: {option!r} is not an option name")
        try:
            value = yaml_scalar(text)
        except ValueError as err:
            raise SolverFlagError(f"{FLAG} {item!r}: the value {err}") from None
        name = canonical_name(solver_info(solver.strip()).name)
        out.setdefault(name, {})[option] = value
    return out


def options_for(solver: str, options: SolverOptions | None) -> dict[str, Any]:
    """Return the options of ``options`` that belong to ``solver`` (aliases resolved)."""
    if not options:
        return {}
    want = canonical_name(solver)
    merged: dict[str, Any] = {}
    for name, opts in options.items():
        if canonical_name(name) == want:
            merged.update(opts)
    return merged


def check_solver_options(options: SolverOptions | None,
                         used: Collection[str] | None = None) -> None:
    """Check command-line options: each names a solver that runs and suits it.

    Parameters
    ----------
    options : mapping, optional
        As returned by :func:`parse_solver_options`.
    used : collection of str, optional
        The solvers that will run; options for another solver are refused (they would
        be silently ignored). None: no such check.

    Raises
    ------
    InvalidInputError
        Options for a solver that does not run, or options the solver refuses (unknown
        name, wrong type, out of range), naming the flag, the option and what is valid.
    """
    if not options:
        return
    running = None if used is None else {canonical_name(s) for s in used}
    for name, opts in options.items():
        if running is not None and canonical_name(name) not in running:
            first = next(iter(opts), "?")
            raise SolverFlagError(
                f"{FLAG} {name}.{first}: solver '{name}' does not run here (running: "
                f"{', '.join(sorted(running)) or 'none'}); its options would be ignored")
        try:
            get_solver(name, **opts)
        except SolverOptionError as err:
            raise flag_error(err) from None
        except InvalidInputError as err:
            raise SolverFlagError(f"{FLAG} for '{name}': {err}") from None


def flag_error(err: SolverOptionError) -> SolverFlagError:
    """Return the command-line form of a refused option."""
    valid = f" (valid: {', '.join(err.valid)})" if err.valid else ""
    return SolverFlagError(f"{FLAG} {err.solver}.{err.option}: {err.reason}{valid}")
