"""Experiments: YAML files in; CSV, JSON and PNG out.

The names below are imported on first access (``from dualarm_qp.experiments import
build_experiment``), not with the package: a module of its own (the figures, drawn in
a process of their own) can be imported without the controller, the solvers and the
configuration schema.
"""

from typing import TYPE_CHECKING as _TYPE_CHECKING

from .._lazy import lazy_names as _lazy_names

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


#: Import a name of :data:`_LAZY` from its module on first access.
__getattr__ = _lazy_names(__name__, globals(), _LAZY)


def __dir__() -> list[str]:
    """List the public names, the lazy ones included."""
    return sorted(__all__)
