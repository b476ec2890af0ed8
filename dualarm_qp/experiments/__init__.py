"""Experiments: YAML files in; CSV, JSON and PNG out.

The names below are imported on first access (``from dualarm_qp.experiments import
build_experiment``), not with the package: a module of its own (the figures, drawn in
a process of their own) can be imported without the controller, the solvers and the
configuration schema.
"""

from importlib import import_module as _import_module
from typing import TYPE_CHECKING as _TYPE_CHECKING
from typing import Any as _Any

if _TYPE_CHECKING:
    from .config import ExperimentConfig, load_config, parse_config
    from .run import RunOutcome, run_experiment
    from .setup import Experiment, build_experiment

#: Names imported on first access, and the module each comes from.
_LAZY = {
    "Experiment": "setup",
    "ExperimentConfig": "config",
    "RunOutcome": "run",
    "build_experiment": "setup",
    "load_config": "config",
    "parse_config": "config",
    "run_experiment": "run",
}

__all__ = [
    "Experiment",
    "ExperimentConfig",
    "RunOutcome",
    "build_experiment",
    "load_config",
    "parse_config",
    "run_experiment",
]


def __getattr__(name: str) -> _Any:
    """Import a name of :data:`_LAZY` from its module on first access."""
    where = _LAZY.get(name)
    if where is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(_import_module(f".{where}", __name__), name)
    globals()[name] = value  # later accesses skip this function
    return value


def __dir__() -> list[str]:
    """List the public names, the lazy ones included."""
    return sorted(__all__)
