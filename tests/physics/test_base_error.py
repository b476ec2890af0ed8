"""A follower's base off its calibration: simulated where the file says, modelled where not."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import yaml

from dualarm_qp.errors import ConfigError
from dualarm_qp.experiments import build_experiment, load_config, parse_config
from dualarm_qp.physics.command import settings_of
from dualarm_qp.physics.plant import MujocoPlant, simulated_task
from dualarm_qp.physics.settings import PhysicsSettings

mujoco = pytest.importorskip("mujoco", reason="the physics check needs MuJoCo "
                                               "(pip install -e '.[physics]'; '.[dev]' has it)")

BEAM = Path(__file__).resolve().parents[2] / "configs" / "puma_beam_limits.yaml"


def test_the_files_base_error_in_si():
    data = yaml.safe_load(BEAM.read_text())  # mm, deg
    data["physics"] = {"base_error": {"position": [3, 0, -1], "rpy": [0, 0.5, 0]}}
    s = settings_of(parse_config(data, "beam.yaml"))
    assert s.base_error is not None
    np.testing.assert_allclose(s.base_error, [3e-3, 0, -1e-3, 0, math.radians(0.5), 0])
    assert s.as_dict()["base_error"]["position_m"] == pytest.approx([3e-3, 0, -1e-3])
    assert settings_of(load_config(BEAM)).base_error is None
    data["physics"] = {"base_error": {"position": [3, 0]}}
    with pytest.raises(ConfigError, match=r"physics\.base_error\.position"):
        parse_config(data, "beam.yaml")


def test_the_simulated_follower_is_off_by_the_error_the_controller_does_not_see(monkeypatch):
    """The error is taken in the base's own frame; MuJoCo's follower tool sits where the
    moved base puts it, the model's where the plan thinks: the follower's weld starts
    stretched by the difference."""
    monkeypatch.setattr(MujocoPlant, "_settle", lambda self: None)
    exp = build_experiment(load_config(BEAM), str(BEAM))
    error = np.array([4e-3, -2e-3, 1e-3, 0.0, 0.0, math.radians(0.3)])
    world = simulated_task(exp.task, error)
    assert simulated_task(exp.task, None) is exp.task
    E = pin.SE3(pin.rpy.rpyToMatrix(0.0, 0.0, math.radians(0.3)), error[:3]).homogeneous
    base = np.asarray(exp.task.follower.base)
    q = exp.initial.q_f
    np.testing.assert_allclose(world.follower.fk(q),
                               base @ E @ np.linalg.inv(base) @ exp.task.follower.fk(q),
                               atol=1e-12)
    plant = MujocoPlant(exp.task, PhysicsSettings(base_error=error))
    plant.reset(exp.initial, exp.options.dt)
    assert plant.task is exp.task and plant.world.follower is not exp.task.follower
    tool = plant.data.body("follower_tool").xpos
    np.testing.assert_allclose(tool, world.follower.fk(q)[:3, 3], atol=1e-9)
    off = np.linalg.norm(world.follower.fk(q)[:3, 3] - exp.task.follower.fk(q)[:3, 3])
    assert off > 2e-3
    assert plant.readout.weld_error(plant.physics.welds["follower"]) == pytest.approx(
        off, rel=1e-6)
    with pytest.raises(ValueError, match="base_error"):
        PhysicsSettings(base_error=np.zeros(5))
