"""The MJCF model against the project's own model: kinematics, masses, the static hold."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from dualarm_qp.experiments import build_experiment, load_config
from dualarm_qp.kinematics.robots import example_robots_dir
from dualarm_qp.physics.mjcf import build_mjcf
from dualarm_qp.physics.settings import PhysicsSettings

mujoco = pytest.importorskip("mujoco", reason="the physics check needs MuJoCo "
                                               "(pip install -e '.[physics]'; '.[dev]' has it)")

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
needs_robots = pytest.mark.skipif(
    example_robots_dir() is None,
    reason="example-robot-data is not installed (pip install -e '.[robots]'; '.[dev]' has it)")

BEAM = CONFIGS / "puma_beam_limits.yaml"          # PUMA 560 from its DH table
UR5 = CONFIGS / "ur5_pair_sliding_bar.yaml"        # UR5 from its URDF
SUPPORT = CONFIGS / "puma_beam_support.yaml"       # a follower that supports


def _experiment(path: Path):
    return build_experiment(load_config(path), str(path))


@pytest.mark.parametrize("config", [BEAM, pytest.param(UR5, marks=needs_robots)],
                         ids=["puma_dh", "ur5_urdf"])
def test_the_models_kinematics_are_pinocchios(config):
    """Tool frames and every joint body agree at random joints to 1e-9."""
    exp = _experiment(config)
    pm = build_mjcf(exp.task, PhysicsSettings())
    model = mujoco.MjModel.from_xml_string(pm.xml)
    data = mujoco.MjData(model)
    rng = np.random.default_rng(7)
    for role, arm in (("leader", exp.task.leader), ("follower", exp.task.follower)):
        adr = [model.jnt_qposadr[model.joint(n).id] for n in pm.joints[role]]
        for _ in range(25):
            q = rng.uniform(-np.pi, np.pi, arm.n)
            data.qpos[adr] = q
            mujoco.mj_kinematics(model, data)
            T = arm.fk(q)
            b = model.body(pm.tools[role]).id
            np.testing.assert_allclose(data.xpos[b], T[:3, 3], rtol=0, atol=1e-9)
            np.testing.assert_allclose(data.xmat[b].reshape(3, 3), T[:3, :3], rtol=0, atol=1e-9)
            frames = arm.link_frames(q)  # joint i's body carries link frame i (both models)
            pin_data = arm.data  # the kernel computes fk: Pinocchio's own data is ours to fill
            pin.forwardKinematics(arm.model, pin_data, q)
            for j in range(1, arm.n + 1):
                body = model.body(f"{role}_link{j}").id
                np.testing.assert_allclose(data.xpos[body],
                                           pin_data.oMi[j].translation, rtol=0, atol=1e-9)
            assert frames.shape == (arm.n + 1, 4, 4)


@needs_robots
def test_urdf_link_masses_are_the_models():
    exp = _experiment(UR5)
    pm = build_mjcf(exp.task, PhysicsSettings())
    model = mujoco.MjModel.from_xml_string(pm.xml)
    for j in range(1, exp.task.leader.n + 1):
        pin_mass = exp.task.leader.model.inertias[j].mass
        assert model.body_mass[model.body(f"leader_link{j}").id] == pytest.approx(pin_mass)
    assert not any("no inertia" in n for n in pm.notes)


def test_a_link_without_inertia_gets_its_capsules_mass_and_says_so():
    exp = _experiment(BEAM)
    settings = PhysicsSettings(link_density=500.0)
    pm = build_mjcf(exp.task, settings)
    model = mujoco.MjModel.from_xml_string(pm.xml)
    arm = exp.task.leader
    for j in range(1, arm.n + 1):
        mass = model.body_mass[model.body(f"leader_link{j}").id]
        if arm.model.inertias[j].mass > 0:
            assert mass == pytest.approx(arm.model.inertias[j].mass)
        else:  # a capsule of volume V weighs 500 V
            assert f"leader_link{j}" in " ".join(pm.notes) and "500 kg/m^3" in " ".join(pm.notes)
            geoms = [g for g in range(model.ngeom) if model.geom_bodyid[g] == model.body(
                f"leader_link{j}").id]
            r, half = model.geom_size[geoms[0]][:2]
            volume = np.pi * r * r * 2 * half + 4 / 3 * np.pi * r ** 3
            if model.geom_type[geoms[0]] == mujoco.mjtGeom.mjGEOM_CAPSULE and len(geoms) == 1:
                assert mass == pytest.approx(500.0 * volume, rel=1e-6)


def test_the_object_is_free_with_its_mass_and_held_by_two_welds():
    exp = _experiment(SUPPORT)  # the file states 4 kg
    pm = build_mjcf(exp.task, PhysicsSettings())
    model = mujoco.MjModel.from_xml_string(pm.xml)
    obj = model.body("object").id
    assert model.body_mass[obj] == pytest.approx(4.0)
    assert model.jnt_type[model.body_jntadr[obj]] == mujoco.mjtJoint.mjJNT_FREE
    assert model.neq == 2 and all(t == mujoco.mjtEq.mjEQ_WELD for t in model.eq_type)
    gap = model.joint(pm.support_gap)
    assert gap.limited and tuple(gap.range) == (-1.0, 0.0)  # pushes, never pulls
