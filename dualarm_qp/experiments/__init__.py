"""Experiments: YAML files in; CSV, JSON and PNG out."""

from .config import ExperimentConfig, load_config, parse_config
from .run import RunOutcome, run_experiment
from .setup import Experiment, build_experiment

__all__ = [
    "Experiment",
    "ExperimentConfig",
    "RunOutcome",
    "build_experiment",
    "load_config",
    "parse_config",
    "run_experiment",
]
