"""The servo gains follow each joint's own inertia, and the integrator's bound holds."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from dualarm_qp.experiments import build_experiment, load_config
from dualarm_qp.kinematics.robots import example_robots_dir
from dualarm_qp.physics.check import closed_loop, diagnose
from dualarm_qp.physics.gains import INTEGRATOR_MARGIN, servo_gains
from dualarm_qp.physics.mjcf import CHAIN_INERTIA, CHAIN_MASS
from dualarm_qp.physics.plant import MujocoPlant
from dualarm_qp.physics.settings import PhysicsSettings

mujoco = pytest.importorskip("mujoco", reason="the physics check needs MuJoCo "
                                               "(pip install -e '.[physics]'; '.[dev]' has it)")

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
BEAM = CONFIGS / "puma_beam_limits.yaml"
UR5 = CONFIGS / "ur5_pair_sliding_bar.yaml"
needs_robots = pytest.mark.skipif(
    example_robots_dir() is None,
    reason="example-robot-data is not installed (pip install -e '.[robots]'; '.[dev]' has it)")


def _experiment(path: Path):
    return build_experiment(load_config(path), str(path))


def _pinocchio_inertia(arm, q, armature: float) -> np.ndarray:
    """``M_ii`` of the arm from Pinocchio's own model: CRBA, the tool body, the armature."""
    model = arm.model.copy()
    tool = model.frames[arm.tool_frame_id]
    body = pin.Inertia(CHAIN_MASS, np.zeros(3), np.eye(3) * CHAIN_INERTIA)
    model.appendBodyToJoint(tool.parentJoint, body, tool.placement)
    data = model.createData()
    return np.diag(pin.crba(model, data, np.asarray(q, dtype=float))) + armature


def _plant_gains(path: Path, settings: PhysicsSettings, monkeypatch):
    monkeypatch.setattr(MujocoPlant, "_settle", lambda self: None)  # the gains are set before
    exp = _experiment(path)
    plant = MujocoPlant(exp.task, settings)
    plant.reset(exp.initial, exp.options.dt)
    inertia = np.r_[_pinocchio_inertia(exp.task.leader, exp.initial.q_l, settings.armature),
                    _pinocchio_inertia(exp.task.follower, exp.initial.q_f, settings.armature)]
    return plant, inertia


def test_each_joint_gain_is_its_own_inertia_times_the_frequency_squared(monkeypatch):
    """The PUMA's joints 2 to 6 (joint 1 also turns link 1, which has no published mass:
    its capsules' in MuJoCo, none in Pinocchio's model)."""
    settings = PhysicsSettings(servo_frequency=30.0, damping_ratio=0.8, armature=0.02)
    plant, inertia = _plant_gains(BEAM, settings, monkeypatch)
    g = plant.gains
    assert g is not None and g.limited == []
    w = 2 * math.pi * 30.0
    outboard = np.r_[1:6, 7:12]
    np.testing.assert_allclose(g.inertia[outboard], inertia[outboard], rtol=1e-9)
    np.testing.assert_allclose(g.kp, g.inertia * w * w, rtol=1e-12)
    np.testing.assert_allclose(g.kv, 2 * 0.8 * g.inertia * w, rtol=1e-12)
    assert g.kp.max() / g.kp.min() > 10  # a shoulder is not a wrist

@pytest.mark.slow
@needs_robots
def test_every_ur5_joint_gain_is_its_own_inertia_times_the_frequency_squared(monkeypatch):
    settings = PhysicsSettings(servo_frequency=30.0, damping_ratio=0.8, armature=0.05)
    plant, inertia = _plant_gains(UR5, settings, monkeypatch)
    g = plant.gains
    assert g is not None and g.limited == []
    w = 2 * math.pi * 30.0
    np.testing.assert_allclose(g.inertia, inertia, rtol=1e-9)
    np.testing.assert_allclose(g.kp, inertia * w * w, rtol=1e-9)
    np.testing.assert_allclose(g.kv, 2 * 0.8 * inertia * w, rtol=1e-9)
    # MuJoCo's actuators carry them: position then velocity per joint.
    np.testing.assert_array_equal(plant.model.actuator_gainprm[0::2, 0], g.kp)
    np.testing.assert_array_equal(plant.model.actuator_biasprm[0::2, 1], -g.kp)
    np.testing.assert_array_equal(plant.model.actuator_gainprm[1::2, 0], g.kv)
    np.testing.assert_array_equal(plant.model.actuator_biasprm[1::2, 2], -g.kv)


def test_a_stated_gain_is_every_joints_and_the_other_follows_the_rule():
    M = np.diag([4.0, 1.0, 0.25])
    arms = {"leader": np.array([0, 1]), "follower": np.array([2])}
    g = servo_gains(M, arms, PhysicsSettings(kp=1e5), 1e-3)
    np.testing.assert_array_equal(g.kp, [1e5, 1e5, 1e5])
    w = 2 * math.pi * 40.0
    np.testing.assert_allclose(g.kv, 2 * np.diag(M) * w)
    g = servo_gains(M, arms, PhysicsSettings(kp=1e5, kv=300.0), 1e-3)
    np.testing.assert_array_equal(g.kv, [300.0] * 3)


def test_a_frequency_the_integrator_cannot_hold_is_lowered_on_the_coupled_modes():
    """The highest mode of M^-1 K, not the diagonal, sets the bound."""
    M = np.zeros((3, 3))
    M[:2, :2] = [[1.0, 0.9], [0.9, 1.0]]  # strongly coupled: lambda = 1 / (1 - 0.9)
    M[2, 2] = 0.5  # the follower: one joint, uncoupled
    arms = {"leader": np.array([0, 1]), "follower": np.array([2])}
    g = servo_gains(M, arms, PhysicsSettings(servo_frequency=100.0), 1e-3)
    assert g.coupling == {"leader": pytest.approx(10.0), "follower": pytest.approx(1.0)}
    assert g.limited == ["leader"]  # 628 rad/s: the follower keeps it
    assert g.omega["follower"] == pytest.approx(2 * math.pi * 100.0)
    assert g.omega["leader"] == pytest.approx(INTEGRATOR_MARGIN / (1e-3 * math.sqrt(10.0)))
    K = np.diag(g.kp[:2])
    highest = math.sqrt(np.linalg.eigvals(np.linalg.solve(M[:2, :2], K)).real.max())
    assert highest * 1e-3 == pytest.approx(INTEGRATOR_MARGIN)


def test_light_wrists_without_armature_are_stable_with_gains_from_their_inertia():
    """One stiff gain for every joint makes the PUMA's light wrists ring without
    armature; each joint's gain from its own inertia does not."""
    exp = _experiment(BEAM)
    short = dataclasses.replace(exp, duration=0.62)  # 20 samples
    settings = PhysicsSettings(armature=0.0)
    run = closed_loop(short, settings)
    judged = diagnose(run, None, settings)
    assert run.result is not None and run.result.completed, run.result.message
    assert judged.oscillation is None and judged.status == "ok", judged.message
    assert run.summary()["deviation_pos_max_m"] < 1e-3
