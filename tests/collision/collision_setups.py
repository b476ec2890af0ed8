"""Shared set-ups of the collision tests: shipped configs with extra keys merged over them."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import yaml

from dualarm_qp.experiments.config import parse_config
from dualarm_qp.experiments.setup import build_experiment

CONFIGS = Path(__file__).resolve().parents[2] / "configs"


def load(name: str) -> dict[str, Any]:
    """The shipped config ``configs/<name>.yaml`` as a dict."""
    return yaml.safe_load((CONFIGS / f"{name}.yaml").read_text())


def merged(data: dict[str, Any], extra: dict[str, Any]) -> dict[str, Any]:
    """``data`` with ``extra`` merged over it, key by key (nested mappings merged too)."""
    out = copy.deepcopy(data)
    for key, value in extra.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = merged(out[key], value)
        else:
            out[key] = copy.deepcopy(value)
    return out


def experiment(name: str, extra: dict[str, Any], solver: str = "nullspace") -> Any:
    """The built experiment of config ``name`` with ``extra`` merged over it."""
    return build_experiment(parse_config(merged(load(name), extra), name), name,
                            solver=solver)
