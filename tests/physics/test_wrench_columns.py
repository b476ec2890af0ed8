"""The hands' measured wrenches: the sensors against the welds, and trajectory.csv's balance."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import yaml

from dualarm_qp.cli import main
from dualarm_qp.experiments import build_experiment, load_config
from dualarm_qp.kinematics.robots import example_robots_dir
from dualarm_qp.physics.mjcf import CHAIN_MASS
from dualarm_qp.physics.plant import MujocoPlant
from dualarm_qp.physics.settings import PhysicsSettings

pytest.importorskip("mujoco", reason="the physics check needs MuJoCo "
                                     "(pip install -e '.[physics]'; '.[dev]' has it)")

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
BEAM = CONFIGS / "puma_beam_limits.yaml"
HEAVY = CONFIGS / "ur5_pair_heavy_bar.yaml"
G = np.array([0.0, 0.0, -9.81])


def test_the_sensors_read_what_the_welds_carry():
    """The wrist sensors, less the tool body's weight, read each weld's force on the
    object (the simulator's own account of it), about the same grasp point."""
    exp = build_experiment(load_config(BEAM), str(BEAM))
    plant = MujocoPlant(exp.task, PhysicsSettings(object_mass=5.0))
    plant.reset(exp.initial, exp.options.dt)
    w_l, w_f, _, _ = plant.wrenches()
    s_l, s_f, _, _ = plant.readout.sensed()
    weight = plant.physics.carried * 9.81
    np.testing.assert_allclose(s_l, w_l, atol=1e-3 * weight)
    np.testing.assert_allclose(s_f, w_f, atol=1e-3 * weight)
    reading = plant.readings[0]
    np.testing.assert_array_equal(reading.leader, s_l)
    assert reading.share == pytest.approx(s_f[2] / (s_l[2] + s_f[2]))
    assert 0.0 < reading.share < 1.0


def _columns(path: Path) -> dict[str, np.ndarray]:
    with path.open() as fh:
        rows = list(csv.DictReader(fh))
    return {k: np.array([float(r[k]) for r in rows]) for k in rows[0]
            if k not in ("status", "clearance_pair")}


def _mass_centre(c: dict[str, np.ndarray], centre: np.ndarray) -> np.ndarray:
    """The object's mass centre [m] from its recorded pose (position, quaternion)."""
    out = []
    for k in range(c["t"].size):
        q = pin.Quaternion(c["object_qw"][k], c["object_qx"][k], c["object_qy"][k],
                           c["object_qz"][k])
        p = np.array([c["object_x"][k], c["object_y"][k], c["object_z"][k]])
        out.append(p + q.toRotationMatrix() @ centre)
    return np.array(out)


@pytest.mark.slow
@pytest.mark.skipif(example_robots_dir() is None,
                    reason="example-robot-data is not installed")
def test_the_measured_wrenches_in_trajectory_csv_balance_the_object(tmp_path):
    """From trajectory.csv alone: at every sample the two measured hand forces, the
    weight of the object (and of its 0.2 kg grasp chain) and its acceleration (second
    differences of its recorded pose) balance: sum f + m g = m a."""
    data = yaml.safe_load(HEAVY.read_text())
    out = tmp_path / "run"
    assert main(["run", str(HEAVY), "--out", str(out), "--quiet", "--no-plots",
                 "--plant", "mujoco"]) == 0
    assert json.loads((out / "summary.json").read_text())["plant"] == "MujocoPlant"
    c = _columns(out / "trajectory.csv")
    mass = data["object"]["mass"] + 2 * CHAIN_MASS  # the chain rides on the object
    centre = np.asarray(data["object"]["mass_centre"], dtype=float) * 1e-3  # mm
    x = _mass_centre(c, centre)
    dt = float(c["t"][1] - c["t"][0])
    a = np.full_like(x, np.nan)
    a[1:-1] = (x[2:] - 2 * x[1:-1] + x[:-2]) / dt ** 2  # the mean over [t - dt, t + dt]
    forces = sum(np.c_[c[f"wrench_{r}_fx"], c[f"wrench_{r}_fy"], c[f"wrench_{r}_fz"]]
                 for r in ("leader", "follower"))
    residual = np.linalg.norm(forces + mass * G - mass * a, axis=1)
    # The second difference is the mean acceleration over two samples, the forces are
    # measured at one instant: allow the change of the mean acceleration next to it.
    change = np.zeros(x.shape[0])
    change[2:-2] = np.maximum(np.linalg.norm(a[3:-1] - a[2:-2], axis=1),
                              np.linalg.norm(a[2:-2] - a[1:-3], axis=1))
    weight = mass * 9.81
    inner = slice(2, -2)
    assert np.all(residual[inner] <= 0.01 * weight + mass * change[inner])
    steady = change < 0.05  # m/s^2: most of the run
    assert steady[inner].mean() > 0.8
    assert np.all(residual[inner][steady[inner]] < 0.005 * weight)
    # The internal part and the share are read from the same two wrenches.
    up = c["wrench_leader_fz"] + c["wrench_follower_fz"]
    np.testing.assert_allclose(c["load_share_follower"], c["wrench_follower_fz"] / up,
                               rtol=1e-9)
    assert np.all(c["internal_force"] >= 0.0)
