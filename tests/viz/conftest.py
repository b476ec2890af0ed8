from __future__ import annotations

import pytest

from dualarm_qp.experiments.config import load_config
from dualarm_qp.experiments.reproduce import bundled_config
from dualarm_qp.experiments.run import run_experiment
from dualarm_qp.experiments.setup import build_experiment

#: A short run of the beam with speed limits (the follower starts outside its ranges).
DURATION_S = 1.5


def _experiment():
    path = bundled_config("puma_beam_limits.yaml")
    exp = build_experiment(load_config(path), str(path))
    exp.duration = DURATION_S
    return exp


@pytest.fixture(scope="session")
def beam():
    return _experiment()


@pytest.fixture(scope="session")
def run_dir(tmp_path_factory):
    """A finished run folder written with --animate's code path."""
    out = tmp_path_factory.mktemp("run")
    run_experiment(_experiment(), out, progress=False, plots=False, animate=True)
    return out
