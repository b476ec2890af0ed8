"""Arms from URDF chains and from example-robot-data: Jacobians, limits, bad input."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from fd import fd_jacobian

from dualarm_qp.errors import InvalidInputError
from dualarm_qp.kinematics import (
    RobotModelError,
    SerialArm,
    example_robot_arm,
    puma560,
    puma560_ik,
    urdf_arm,
)
from dualarm_qp.kinematics.robots import (
    EXAMPLE_ROBOTS,
    example_robot_urdf,
    example_robots_dir,
)

needs_robots = pytest.mark.skipif(
    example_robots_dir() is None,
    reason="example-robot-data is not installed (pip install -e '.[robots]'; '.[dev]' has it)")

#: (robot, root, tip) of every shipped chain we support: each robot of
#: ``EXAMPLE_ROBOTS``, and Baxter's two arms from their mounts and from the robot's base.
CHAINS = [
    ("ur3", "base_link", "tool0"),
    ("ur5", "base_link", "tool0"),
    ("ur10", "base_link", "tool0"),
    ("panda", "panda_link0", "panda_link8"),
    ("xarm7", "link_base", "link_eef"),
    ("z1", "link00", "link06"),
    ("baxter", "left_arm_mount", "left_gripper"),
    ("baxter", "base", "left_gripper"),
    ("baxter", "base", "right_gripper"),
    ("kinova", "base", "j2s6s200_end_effector"),  # three continuous joints
]


def random_pose(rng: np.random.Generator, scale: float = 1.0) -> np.ndarray:
    return pin.SE3(pin.exp3(rng.normal(size=3)), scale * rng.normal(size=3)).homogeneous


def urdf_limits(path: Path, joints: list[str]) -> tuple[np.ndarray, ...]:
    """``lower``, ``upper`` and ``velocity`` of the joints' limit tags, read as XML.

    A continuous joint has no range (-inf, inf), whatever its tag says.
    """
    found = {j.get("name"): j for j in ET.parse(path).getroot().findall("joint")}
    tags = {name: j.find("limit") for name, j in found.items()}
    endless = {name for name, j in found.items() if j.get("type") == "continuous"}
    lo, hi, vel = ([float(tags[name].get(k)) for name in joints]  # type: ignore[union-attr, arg-type]
                   for k in ("lower", "upper", "velocity"))
    for i, name in enumerate(joints):
        if name in endless:
            lo[i], hi[i] = -np.inf, np.inf
    return np.array(lo), np.array(hi), np.array(vel)


def check_jacobian(arm: SerialArm, seed: int) -> None:
    rng = np.random.default_rng(seed)
    lo = np.where(np.isfinite(arm.q_min), arm.q_min, -np.pi)
    hi = np.where(np.isfinite(arm.q_max), arm.q_max, np.pi)
    for _ in range(20):
        placed = arm.with_base(random_pose(rng))
        placed.tool = random_pose(rng, 0.2)
        q = rng.uniform(lo, hi)
        T, J = placed.fk_jacobian(q)
        assert J.shape == (6, arm.n) and J.flags.c_contiguous
        np.testing.assert_allclose(T, placed.fk(q), rtol=0, atol=1e-14)
        np.testing.assert_allclose(J, placed.jacobian(q), rtol=0, atol=0)
        np.testing.assert_allclose(J, fd_jacobian(placed, q), rtol=0, atol=1e-8)


def test_puma_from_dh_jacobian_matches_finite_differences() -> None:
    check_jacobian(puma560(), 0)


@needs_robots
@pytest.mark.parametrize(("robot", "root", "tip"), CHAINS)
def test_shipped_chain_jacobian_matches_finite_differences(robot: str, root: str,
                                                            tip: str) -> None:
    check_jacobian(example_robot_arm(robot, root, tip), 1)


def test_every_shipped_robot_has_a_checked_chain() -> None:
    """A robot added to EXAMPLE_ROBOTS without a chain here would go untested."""
    assert {robot for robot, _, _ in CHAINS} == set(EXAMPLE_ROBOTS)


@needs_robots
@pytest.mark.parametrize(("robot", "root", "tip"), CHAINS)
def test_shipped_chain_limits_come_from_the_urdf(robot: str, root: str, tip: str) -> None:
    arm = example_robot_arm(robot, root, tip)
    lo, hi, vel = urdf_limits(example_robot_urdf(robot), arm.joint_names)
    np.testing.assert_array_equal(arm.q_min, lo)
    np.testing.assert_array_equal(arm.q_max, hi)
    np.testing.assert_array_equal(arm.qd_max, vel)
    override = example_robot_arm(robot, root, tip, qd_max=0.5)
    np.testing.assert_array_equal(override.qd_max, np.full(arm.n, 0.5))
    np.testing.assert_array_equal(override.q_min, lo)
    slower = arm.with_limits(qd_max=vel / 2)
    np.testing.assert_array_equal(slower.qd_max, vel / 2)
    np.testing.assert_array_equal(slower.q_max, hi)
    np.testing.assert_array_equal(arm.qd_max, vel)


@needs_robots
def test_baxter_arms_are_the_full_robot_with_the_rest_at_zero() -> None:
    """Left and right chains agree with Pinocchio's whole Baxter (other joints at 0)."""
    full = pin.buildModelFromUrdf(str(example_robot_urdf("baxter")))
    data = full.createData()
    rng = np.random.default_rng(2)
    for side in ("left", "right"):
        from_base = example_robot_arm("baxter", "base", f"{side}_gripper")
        from_mount = example_robot_arm("baxter", f"{side}_arm_mount", f"{side}_gripper")
        assert from_base.joint_names == [f"{side}_{j}" for j in
                                         ("s0", "s1", "e0", "e1", "w0", "w1", "w2")]
        q = rng.uniform(from_base.q_min, from_base.q_max)
        qf = pin.neutral(full)
        for name, qi in zip(from_base.joint_names, q, strict=True):
            qf[full.idx_qs[full.getJointId(name)]] = qi
        pin.framesForwardKinematics(full, data, qf)
        T_tip = data.oMf[full.getFrameId(f"{side}_gripper")].homogeneous
        T_mount = data.oMf[full.getFrameId(f"{side}_arm_mount")].homogeneous
        np.testing.assert_allclose(from_base.fk(q), T_tip, rtol=0, atol=1e-12)
        np.testing.assert_allclose(from_mount.with_base(T_mount).fk(q), T_tip, rtol=0,
                                   atol=1e-12)
        frames = from_mount.link_frames(q)
        assert frames.shape == (8, 4, 4)
        np.testing.assert_allclose(frames[0], np.eye(4), atol=0)


@needs_robots
def test_bad_example_robot_input() -> None:
    with pytest.raises(RobotModelError, match="unknown robot 'nao'") as err:
        example_robot_arm("nao", "a", "b")
    assert err.value.field == "name"
    with pytest.raises(RobotModelError, match="root frame 'left_mount' not found") as err:
        example_robot_arm("baxter", "left_mount", "left_gripper")
    assert err.value.field == "root"
    with pytest.raises(RobotModelError, match="not below root") as err:
        example_robot_arm("baxter", "left_arm_mount", "right_gripper")
    assert err.value.field == "tip"
    with pytest.raises(RobotModelError, match="no joint between") as err:
        example_robot_arm("baxter", "left_gripper", "left_gripper")
    with pytest.raises(InvalidInputError, match="needs an arm built from a DH table"):
        puma560_ik(example_robot_arm("ur5", "base_link", "tool0"), np.eye(4))


# A two-link planar arm, written by hand: joint a (z, at the origin), link 0.5 along x,
# joint b (z), link 0.3 along x to the tip. Joint c is another branch, locked.
TWO_LINK = """<?xml version="1.0"?>
<robot name="two_link">
  <link name="world"/><link name="l1"/><link name="l2"/><link name="tip"/><link name="side"/>
  <joint name="a" type="{kind_a}">
    <parent link="world"/><child link="l1"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="2" velocity="{vel_a}" effort="1"/>
  </joint>
  <joint name="b" type="revolute">
    <parent link="l1"/><child link="l2"/><origin xyz="0.5 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="0.5" velocity="1.5" effort="1"/>
  </joint>
  <joint name="t" type="fixed">
    <parent link="l2"/><child link="tip"/><origin xyz="0.3 0 0"/>
  </joint>
  <joint name="c" type="revolute">
    <parent link="world"/><child link="side"/><axis xyz="1 0 0"/>
    <limit lower="-1" upper="1" velocity="1" effort="1"/>
  </joint>
</robot>
"""


def write_urdf(tmp_path: Path, kind_a: str = "revolute", vel_a: str = "2") -> Path:
    path = tmp_path / "two_link.urdf"
    path.write_text(TWO_LINK.format(kind_a=kind_a, vel_a=vel_a))
    return path


def test_hand_written_urdf_chain(tmp_path: Path) -> None:
    arm = urdf_arm(write_urdf(tmp_path), "world", "tip")
    assert arm.n == 2 and arm.joint_names == ["a", "b"] and arm.dh is None
    np.testing.assert_array_equal(arm.q_min, [-1, -3])
    np.testing.assert_array_equal(arm.q_max, [2, 0.5])
    np.testing.assert_array_equal(arm.qd_max, [2, 1.5])
    q = np.array([0.4, -0.9])
    expected = [0.5 * np.cos(0.4) + 0.3 * np.cos(-0.5), 0.5 * np.sin(0.4) + 0.3 * np.sin(-0.5)]
    np.testing.assert_allclose(arm.fk(q)[:2, 3], expected, rtol=0, atol=1e-15)
    np.testing.assert_allclose(arm.jacobian(q), fd_jacobian(arm, q), atol=1e-9)
    from_l1 = urdf_arm(write_urdf(tmp_path), "l1", "tip")  # root below a chain joint
    assert from_l1.joint_names == ["b"]
    np.testing.assert_allclose(from_l1.fk([0.0])[:3, 3], [0.8, 0, 0], atol=1e-15)


def test_urdf_speed_zero_means_no_limit(tmp_path: Path) -> None:
    arm = urdf_arm(write_urdf(tmp_path, vel_a="0"), "world", "tip")
    np.testing.assert_array_equal(arm.qd_max, [np.inf, 1.5])


def test_urdf_prismatic_joint_refused(tmp_path: Path) -> None:
    with pytest.raises(RobotModelError, match="joint 'a' is prismatic") as err:
        urdf_arm(write_urdf(tmp_path, kind_a="prismatic"), "world", "tip")
    assert err.value.field == "chain"
    urdf_arm(write_urdf(tmp_path, kind_a="prismatic"), "l1", "tip")  # not in the chain: locked


@pytest.mark.parametrize("axis", ["0 0 1", "0 0.6 0.8", "0 -1 0"])
def test_urdf_continuous_joint_is_one_angle_without_range(tmp_path: Path, axis: str) -> None:
    """A continuous joint is a revolute joint of range +-inf: one angle, not wrapped, the
    same kinematics as the revolute joint of the same axis, its speed and effort kept."""
    text = TWO_LINK.format(kind_a="continuous", vel_a="2").replace(
        '<axis xyz="0 0 1"/>', f'<axis xyz="{axis}"/>', 1)
    (tmp_path / "continuous.urdf").write_text(text)
    (tmp_path / "revolute.urdf").write_text(text.replace('"continuous"', '"revolute"'))
    arm = urdf_arm(tmp_path / "continuous.urdf", "world", "tip")
    same = urdf_arm(tmp_path / "revolute.urdf", "world", "tip")
    assert arm.n == 2 and arm.model.nq == 2 and arm.joint_names == ["a", "b"]
    np.testing.assert_array_equal(arm.q_min, [-np.inf, -3])
    np.testing.assert_array_equal(arm.q_max, [np.inf, 0.5])
    np.testing.assert_array_equal(arm.qd_max, [2, 1.5])
    np.testing.assert_array_equal(arm.model.effortLimit, [1, 1])
    rng = np.random.default_rng(4)
    for q in ([0.0, 0.0], [7.5, -0.4], *rng.uniform(-10, 10, (10, 2))):
        q = np.asarray(q, dtype=float)
        np.testing.assert_allclose(arm.fk(q), same.fk(q), rtol=0, atol=1e-14)
        np.testing.assert_allclose(arm.jacobian(q), fd_jacobian(arm, q), atol=1e-9)
    np.testing.assert_allclose(arm.fk([0.3 + 2 * np.pi, 0.2]), arm.fk([0.3, 0.2]),
                               atol=1e-14)  # a turn on: the same pose, another angle
    ranged = urdf_arm(tmp_path / "continuous.urdf", "world", "tip", q_min=[-4, -3],
                      q_max=[4, 0.5])
    np.testing.assert_array_equal(ranged.q_min, [-4, -3])


def test_bad_urdf_files(tmp_path: Path) -> None:
    with pytest.raises(RobotModelError, match="not found") as err:
        urdf_arm(tmp_path / "missing.urdf", "world", "tip")
    assert err.value.field == "file"
    bad = tmp_path / "bad.urdf"
    bad.write_text("<robot name='x'><link name='a'>")
    with pytest.raises(RobotModelError, match="cannot read URDF") as err:
        urdf_arm(bad, "world", "tip")
    assert err.value.field == "file"
    with pytest.raises(RobotModelError, match="tip frame 'hand' not found") as err:
        urdf_arm(write_urdf(tmp_path), "world", "hand")
    assert err.value.field == "tip"


@needs_robots
def test_kinova_continuous_joints_are_its_urdf_made_revolute(tmp_path: Path) -> None:
    """The Jaco with its three continuous joints equals the same URDF with them typed
    revolute: the same poses, Jacobians, inertias (hence joint torques), efforts and
    speed limits, one coordinate per joint; only the ranges differ (none, where the
    revolute copy reads the limit tags' +-2 pi)."""
    from dualarm_qp.task.torques import ArmStatics

    path = example_robot_urdf("kinova")
    assert path.read_text().count('type="continuous"') == 3
    copy = tmp_path / "kinova_revolute.urdf"
    copy.write_text(path.read_text().replace('type="continuous"', 'type="revolute"'))
    arm = example_robot_arm("kinova", "base", "j2s6s200_end_effector")
    same = urdf_arm(copy, "base", "j2s6s200_end_effector")
    assert arm.model.nq == arm.model.nv == 6 and arm.joint_names == same.joint_names
    endless = [0, 3, 5]
    np.testing.assert_array_equal(arm.q_min[endless], -np.inf)
    np.testing.assert_array_equal(arm.q_max[endless], np.inf)
    np.testing.assert_array_equal(same.q_max[endless], 6.28318530718)
    np.testing.assert_array_equal(arm.q_min[[1, 2, 4]], same.q_min[[1, 2, 4]])
    np.testing.assert_array_equal(arm.qd_max, same.qd_max)
    np.testing.assert_array_equal(arm.model.effortLimit, same.model.effortLimit)
    for j in range(1, arm.model.njoints):
        assert arm.model.inertias[j] == same.model.inertias[j]
    rng = np.random.default_rng(5)
    g = np.array([0.0, 0.0, -9.81])
    statics, statics_same = ArmStatics(arm, g), ArmStatics(same, g)
    for q in rng.uniform(-7.0, 7.0, (10, 6)):
        np.testing.assert_allclose(arm.fk(q), same.fk(q), rtol=0, atol=1e-15)
        np.testing.assert_allclose(arm.jacobian(q), same.jacobian(q), rtol=0, atol=1e-15)
        np.testing.assert_allclose(statics.torque(q, np.zeros(6)),
                                   statics_same.torque(q, np.zeros(6)), rtol=0, atol=1e-12)
