from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from dualarm_qp.experiments.config import load_config
from dualarm_qp.experiments.reproduce import bundled_config
from dualarm_qp.experiments.run import run_experiment
from dualarm_qp.experiments.setup import build_experiment

#: A short run of the beam with speed limits (the follower starts outside its ranges).
DURATION_S = 1.5
#: A short run of the UR5 pair (its page holds the arms' meshes).
UR5_DURATION_S = 1.0
#: The beam with collision avoidance and a pillar beside the follower (file units, mm):
#: the follower's link1 starts 42 mm from it, within the influence distance (100 mm).
PILLAR = {"collision": {"enabled": True},
          "scene": {"obstacles": [{"name": "pillar", "capsule": {"radius": 50, "length": 1200},
                                   "pose": {"position": [450, 1230, 0]}}]}}


def _experiment():
    path = bundled_config("puma_beam_limits.yaml")
    exp = build_experiment(load_config(path), str(path))
    exp.duration = DURATION_S
    return exp


def pillar_experiment(folder: Path, duration: float = DURATION_S):
    """The beam of puma_beam_limits.yaml with :data:`PILLAR`, written into ``folder``."""
    raw = yaml.safe_load(bundled_config("puma_beam_limits.yaml").read_text())
    raw.update(PILLAR, name="puma_beam_pillar")
    raw["controller"]["duration"] = duration
    path = folder / "pillar.yaml"
    path.write_text(yaml.safe_dump(raw))
    return build_experiment(load_config(path), str(path))


@pytest.fixture(scope="session")
def beam():
    return _experiment()


@pytest.fixture(scope="session")
def pillar(tmp_path_factory):
    """The beam with a collision scene: a pillar near the follower."""
    return pillar_experiment(tmp_path_factory.mktemp("pillar"))


@pytest.fixture(scope="session")
def pillar_run_dir(pillar, tmp_path_factory):
    """A finished, animated run folder of :func:`pillar`."""
    out = tmp_path_factory.mktemp("pillarrun")
    run_experiment(pillar, out, progress=False, plots=False, animate=True)
    return out


@pytest.fixture(scope="session")
def ur5_pair():
    """The UR5 pair of configs/ur5_pair_sliding_bar.yaml (example-robot-data needed)."""
    from dualarm_qp.kinematics.robots import example_robots_dir

    if example_robots_dir() is None:
        pytest.skip("example-robot-data is not installed (pip install 'dualarm-qp[robots]')")
    path = Path(__file__).resolve().parents[2] / "configs" / "ur5_pair_sliding_bar.yaml"
    exp = build_experiment(load_config(path), str(path))
    exp.duration = UR5_DURATION_S
    return exp


@pytest.fixture(scope="session")
def ur5_run_dir(ur5_pair, tmp_path_factory):
    """A finished, animated run folder of the UR5 pair (meshes drawn)."""
    out = tmp_path_factory.mktemp("ur5run")
    run_experiment(ur5_pair, out, progress=False, plots=False, animate=True)
    return out


@pytest.fixture(scope="session")
def run_dir(tmp_path_factory):
    """A finished run folder written with --animate's code path."""
    out = tmp_path_factory.mktemp("run")
    run_experiment(_experiment(), out, progress=False, plots=False, animate=True)
    return out
