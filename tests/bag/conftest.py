"""What the bag tests share: a short finished run of the beam with speed limits."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from dualarm_qp.experiments.config import load_config
from dualarm_qp.experiments.run import run_experiment
from dualarm_qp.experiments.setup import build_experiment

CONFIG = Path(__file__).resolve().parents[2] / "configs" / "puma_beam_limits.yaml"


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    """A short finished run of the beam with speed limits (1 s, no plots)."""
    exp = build_experiment(load_config(CONFIG), str(CONFIG))
    exp = dataclasses.replace(exp, duration=1.0)
    out = tmp_path_factory.mktemp("run")
    run_experiment(exp, out, progress=False, plots=False)
    return out
