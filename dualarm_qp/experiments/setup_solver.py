"""The solver of an experiment: its options (the file's and the command line's), its fallback.

The file's ``solver.options`` belong to the file's solver: they are checked against it
(when it is installed) and handed to the solver only when the solver that runs is that
one (no ``solver`` given to :func:`~.setup.build_experiment`, or the same name); another
solver runs with its defaults and its own command-line options (``--solver-option``).
Each set is checked by the solver itself: a refusal names the file's key, or the
command-line option.
"""

from __future__ import annotations

from typing import Any

from ..errors import ConfigError, DualArmError, SolverNotFoundError
from ..solvers.registry import (
    SolverInfo,
    SolverOptionError,
    canonical_name,
    get_solver,
    solver_info,
)
from .config import ExperimentConfig
from .options import SolverFlagError, SolverOptions, flag_error, options_for


def solver_options_of(cfg: ExperimentConfig, path: str, solver: str | None,
                      cli: SolverOptions | None) -> dict[str, Any]:
    """Return the options the running solver gets (:func:`~.setup.build_experiment`), checked."""
    own = cfg.solver.options
    file_info = None
    try:
        file_info = solver_info(cfg.solver.name)
    except SolverNotFoundError as err:
        if solver is None:  # the file's solver runs: a wrong name is an error in the file
            raise ConfigError(str(err), path=path, key="solver.name") from None
    if own and file_info is not None:  # options the file's solver refuses: the file's fault
        try:
            get_solver(cfg.solver.name, **own)
        except SolverOptionError as err:
            raise ConfigError(err.reason, path=path, key=f"solver.options.{err.option}",
                              valid=err.valid) from None
        except DualArmError as err:
            raise ConfigError(str(err), path=path, key="solver.options") from None
    running = solver or cfg.solver.name
    same = canonical_name(running) == canonical_name(cfg.solver.name)
    extra = options_for(running, cli)
    chosen = {**(own if same else {}), **extra}
    if extra:
        try:
            solver_info(running)
        except SolverNotFoundError:
            return chosen  # reported by its own message when the solver is built
        try:
            get_solver(running, **chosen)
        except SolverOptionError as err:
            if err.option in extra:
                raise flag_error(err) from None
            raise ConfigError(err.reason, path=path, key=f"solver.options.{err.option}",
                              valid=err.valid) from None
        except DualArmError as err:
            raise SolverFlagError(f"--solver-option for '{running}': {err}") from None
    return chosen


def _solver_info_or_none(name: str) -> SolverInfo | None:
    """Return the registry entry of ``name``, or None when there is none."""
    try:
        return solver_info(name)
    except SolverNotFoundError:
        return None


def fallback_of(cfg: ExperimentConfig, path: str) -> str | None:
    """Return the file's fallback solver (None for ``"none"``): installed, with hard limits."""
    fallback = None if cfg.solver.fallback == "none" else cfg.solver.fallback
    if fallback is not None:
        try:
            info = solver_info(fallback)
        except SolverNotFoundError as err:
            raise ConfigError(str(err), path=path, key="solver.fallback") from None
        if not (info.hard_bounds and info.available):
            raise ConfigError("the fallback must be an installed solver that keeps hard "
                              "limits (or 'none')", path=path, key="solver.fallback",
                              valid=["nullspace", "none"]) from None
    return fallback


def check_projection(cfg: ExperimentConfig, solver_name: str, path: str) -> None:
    """Refuse ``controller.projection`` for a solver that keeps hard limits."""
    chosen = _solver_info_or_none(solver_name)
    if cfg.controller.projection and chosen is not None and chosen.hard_bounds:
        raise ConfigError(f"solver '{solver_name}' keeps hard limits; the position-level "
                          "projection is unbounded and would break them (drift is "
                          "corrected through the step's feedback term)", path=path,
                          key="controller.projection", valid=["false"]) from None


__all__ = ["check_projection", "fallback_of", "solver_options_of"]
