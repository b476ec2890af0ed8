"""The compiled kernel's kinematics against Python Pinocchio, on the very same models.

The arms (DH standard and modified, URDF chains) and the carried-object model are built
in Python; the kernel rebuilds each model from arrays and computes there. Its poses and
LOCAL_WORLD_ALIGNED frame Jacobians must equal Pinocchio's Python calls on the Python
model to 1e-12, and its Jacobians the finite differences of its poses.
"""

from __future__ import annotations

import copy
import importlib
import pickle

import numpy as np
import pinocchio as pin
import pytest
from fd import fd_jacobian
from hypothesis import given, settings
from hypothesis import strategies as st

from dualarm_qp import _compiled
from dualarm_qp._compiled import check_pinocchio, kernel
from dualarm_qp.errors import DualArmError, InvalidInputError, KernelError
from dualarm_qp.kinematics import DHTable, SerialArm, example_robot_arm, puma560
from dualarm_qp.kinematics.compiled import compiled_chain
from dualarm_qp.kinematics.robots import example_robots_dir
from dualarm_qp.step.context import ArmKinematics
from dualarm_qp.task.carry import CarryModel
from dualarm_qp.task.surfaces import CurvedBar, PlaneBar

LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
SETTINGS = settings(max_examples=25, deadline=None)
HAS_ROBOTS = example_robots_dir() is not None


def random_pose(rng: np.random.Generator, scale: float = 1.0) -> np.ndarray:
    return pin.SE3(pin.exp3(rng.normal(size=3)), scale * rng.normal(size=3)).homogeneous


def modified_dh() -> SerialArm:
    """A 6-joint modified-DH (Craig) arm with offsets and every kind of twist."""
    rows = [(0.0, 0.0, 0.3, 0.1), (0.05, -np.pi / 2, 0.0, -0.3), (0.4, 0.0, 0.02, 0.0),
            (0.03, -np.pi / 2, 0.35, 0.2), (0.0, np.pi / 2, 0.0, 0.0),
            (0.0, -0.7, 0.08, 0.5)]
    return SerialArm(DHTable.from_rows(np.array(rows), "modified"), name="craig")


ARMS = {"puma560": puma560, "modified_dh": modified_dh}
if HAS_ROBOTS:
    ARMS["ur5"] = lambda: example_robot_arm("ur5", "base_link", "tool0")
    ARMS["panda"] = lambda: example_robot_arm("panda", "panda_link0", "panda_link8")
_BUILT: dict[str, SerialArm] = {}


def arm_named(name: str) -> SerialArm:
    if name not in _BUILT:
        _BUILT[name] = ARMS[name]()
    return _BUILT[name]


def python_kinematics(model, frames, q):
    """Pinocchio's Python calls: every frame's pose and LWA Jacobian at q."""
    data = model.createData()
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    return ([data.oMf[f].homogeneous for f in frames],
            [pin.getFrameJacobian(model, data, f, LWA) for f in frames])


@SETTINGS
@given(name=st.sampled_from(sorted(ARMS)), seed=st.integers(0, 2**32 - 1))
def test_arm_kinematics_equal_python_pinocchio(name: str, seed: int) -> None:
    rng = np.random.default_rng(seed)
    arm = arm_named(name).with_base(random_pose(rng))
    arm.tool = random_pose(rng, 0.2)
    lo = np.where(np.isfinite(arm.q_min), arm.q_min, -np.pi)
    hi = np.where(np.isfinite(arm.q_max), arm.q_max, np.pi)
    q = rng.uniform(lo, hi)
    frames = [arm.tool_frame_id, *arm.link_frame_ids]
    poses, jacobians = python_kinematics(arm.model, frames, q)
    T, J = arm.fk_jacobian(q)
    np.testing.assert_allclose(T, poses[0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(J, jacobians[0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(arm.fk(q), poses[0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(arm.link_frames(q), np.array(poses[1:]), rtol=0, atol=1e-12)
    # The link frames' Jacobians (collision rows) read after the step's one call.
    arm.fk_jacobian(q)
    view = ArmKinematics(arm.model, arm.data, arm.n, arm.chain)
    for f, J_py in zip(frames, jacobians, strict=True):
        np.testing.assert_allclose(view.frame_jacobian(f), J_py, rtol=0, atol=1e-12)
    np.testing.assert_allclose(J, fd_jacobian(arm, q), rtol=0, atol=1e-8)


@pytest.mark.parametrize("name", sorted(ARMS))
def test_every_frame_of_the_model_is_the_same(name: str) -> None:
    """Frame ids are shared: every frame of the Python model, poses and Jacobians."""
    arm = arm_named(name).with_base(random_pose(np.random.default_rng(4)))
    q = np.random.default_rng(5).uniform(-1.0, 1.0, arm.n)
    frames = list(range(1, len(arm.model.frames)))  # 0 is the universe, no frame of ours
    poses, jacobians = python_kinematics(arm.model, frames, q)
    P, J = np.empty((4 * len(frames), 4)), np.empty((6 * len(frames), arm.n))
    arm.chain.compute(q, frames, frames, P, J)
    np.testing.assert_allclose(P.reshape(-1, 4, 4), np.array(poses), rtol=0, atol=1e-12)
    np.testing.assert_allclose(J.reshape(-1, 6, arm.n), np.array(jacobians), rtol=0,
                               atol=1e-12)


@pytest.mark.parametrize("name", list(ARMS))
def test_poses_at_other_joints_leave_the_chains_kinematics(name: str) -> None:
    """``Chain.poses`` (what ``fk``, the support line and the look-ahead ask) computes the
    poses at other joints by forward kinematics alone, in a workspace of its own: the same
    poses as an update to the bit, and the chain keeps its joints, its update count, its
    poses and its Jacobians."""
    arm = arm_named(name)
    chain = compiled_chain(arm.model)
    rng = np.random.default_rng(5)
    q_step, q_other = rng.uniform(-1.0, 1.0, (2, chain.nq))
    frames = list(range(chain.nframes))
    chain.update(q_step)
    before_T = np.empty((4 * len(frames), 4))
    chain.frame_poses(frames, before_T)
    before_J = np.empty((6, chain.nq))
    chain.frame_jacobian(frames[-1], before_J)
    count = chain.updates
    T = np.empty((4 * len(frames), 4))
    chain.poses(q_other, frames, T)
    assert chain.updates == count and np.array_equal(chain.q, q_step)
    after_T = np.empty_like(before_T)
    chain.frame_poses(frames, after_T)
    after_J = np.empty_like(before_J)
    chain.frame_jacobian(frames[-1], after_J)
    assert np.array_equal(after_T, before_T) and np.array_equal(after_J, before_J)
    chain.update(q_other)  # what an update gives at q_other: the same poses, to the bit
    want = np.empty_like(T)
    chain.frame_poses(frames, want)
    assert np.array_equal(T, want)


def test_base_and_tool_edits_reach_the_kernel() -> None:
    rng = np.random.default_rng(3)
    arm = puma560()
    q = rng.uniform(-1.0, 1.0, 6)
    before = arm.fk(q)
    arm.base = B = random_pose(rng)
    arm.tool = X = random_pose(rng, 0.1)
    np.testing.assert_allclose(arm.fk(q), B @ before @ X, rtol=0, atol=1e-12)
    moved = arm.with_base(np.eye(4))
    np.testing.assert_allclose(moved.fk(q), before @ X, rtol=0, atol=1e-12)
    assert moved.chain is not arm.chain


@pytest.mark.parametrize("leader", [None, "curved"])
@pytest.mark.parametrize("follower", ["plane", "curved"])
def test_carried_object_model_equals_python_pinocchio(follower: str, leader: str | None
                                                      ) -> None:
    surfaces = {"plane": lambda: PlaneBar(origin=(0.01, 0.02, -0.05), sliding=(0.6, 0.0, 0.8),
                                          normal=(0.8, 0.0, -0.6), r_min=(-1, -1, -1),
                                          r_max=(1, 1, 1), sigma_min=-0.2, sigma_max=0.4),
                "curved": lambda: CurvedBar(0.5, sigma_min=-0.2, sigma_max=0.3)}
    rng = np.random.default_rng(7)
    arm = puma560(base=random_pose(rng), tool=random_pose(rng, 0.1))
    carry = CarryModel(arm, surfaces[follower](), random_pose(rng, 0.1),
                       None if leader is None else surfaces[leader]())
    frames = list(range(1, len(carry.model.frames)))
    view = ArmKinematics(carry.model, carry.data, 6, carry.chain)
    for _ in range(5):
        kin = carry.update(rng.uniform(-2.0, 2.0, 6), rng.uniform(-0.2, 0.3),
                           rng.uniform(-0.2, 0.3))
        poses, jacobians = python_kinematics(carry.model, frames, carry.chain.q)
        tool = arm.tool_frame_id - 1
        np.testing.assert_allclose(kin.T_tool, poses[tool], rtol=0, atol=1e-12)
        np.testing.assert_allclose(kin.J_tool, jacobians[tool][:, :6], rtol=0, atol=1e-12)
        for k, f in enumerate(frames):
            np.testing.assert_allclose(view.frame_pose(f), poses[k], rtol=0, atol=1e-12)
            J = np.empty((6, carry.model.nv))
            carry.chain.frame_jacobian(f, J)
            np.testing.assert_allclose(J, jacobians[k], rtol=0, atol=1e-12)


def test_moved_follower_path_reaches_the_kernel() -> None:
    rng = np.random.default_rng(8)
    arm = puma560()
    first = PlaneBar(origin=(0, 0, 0), sliding=(1, 0, 0), normal=(0, 0, 1), r_min=(-1, -1, -1),
                     r_max=(1, 1, 1), sigma_min=-0.5, sigma_max=0.5)
    other = PlaneBar(origin=(0.1, 0, 0), sliding=(0, 0.6, 0.8), normal=(0, 0.8, -0.6),
                     r_min=(-1, -1, -1), r_max=(1, 1, 1), sigma_min=-0.5, sigma_max=0.5)
    H1 = random_pose(rng, 0.1)
    carry = CarryModel(arm, first, H1)
    q = rng.uniform(-1.0, 1.0, 6)
    carry.place_follower(other)
    moved = carry.update(q, 0.2)
    fresh = CarryModel(arm, other, H1).update(q, 0.2)
    np.testing.assert_allclose(moved.T_target, fresh.T_target, rtol=0, atol=1e-14)
    np.testing.assert_allclose(moved.J_target, fresh.J_target, rtol=0, atol=1e-14)


def test_arm_kinematics_reads_the_step_and_fills_pinocchio_data_on_demand() -> None:
    arm = puma560(base=random_pose(np.random.default_rng(1)))
    view = ArmKinematics(arm.model, arm.data, arm.n, arm.chain)
    q = np.array([0.1, -0.4, 0.3, 0.2, 0.5, -0.6])
    arm.fk_jacobian(q)
    links = arm.link_frame_ids
    np.testing.assert_allclose(view.frame_poses(links), arm.link_frames(q), rtol=0, atol=0)
    data = view.data  # a user's limit calling Pinocchio itself sees this step's joints
    for f in links:
        np.testing.assert_allclose(data.oMf[f].homogeneous, view.frame_pose(f), rtol=0,
                                   atol=1e-12)
    q2 = q + 0.3
    arm.fk_jacobian(q2)
    np.testing.assert_allclose(view.data.oMf[arm.tool_frame_id].homogeneous, arm.fk(q2),
                               rtol=0, atol=1e-12)


def test_joint_the_kernel_cannot_take_is_refused() -> None:
    model = pin.Model()
    model.addJoint(0, pin.JointModelSpherical(), pin.SE3.Identity(), "ball")
    with pytest.raises(InvalidInputError, match="ball"):
        compiled_chain(model)


def test_kernel_chain_refuses_malformed_arrays() -> None:
    T = np.eye(4)
    with pytest.raises(ValueError, match="parent"):
        kernel.Chain([1], [2], np.zeros((1, 3)), T, [], np.zeros((0, 4)))
    with pytest.raises(ValueError, match="kind"):
        kernel.Chain([0], [9], np.zeros((1, 3)), T, [], np.zeros((0, 4)))
    chain = kernel.Chain([0], [2], np.zeros((1, 3)), T, [1], T)
    with pytest.raises(ValueError, match="entries"):
        chain.update(np.zeros(2))
    chain.update(np.zeros(1))
    out = np.empty((4, 4))
    with pytest.raises(IndexError):
        chain.frame_poses([2], out)
    with pytest.raises(ValueError, match="T must be"):
        chain.frame_poses([1, 1], out)
    with pytest.raises(TypeError):  # the outputs are written in place: never converted
        chain.frame_poses([1], np.empty((4, 4), dtype=np.float32))
    with pytest.raises(IndexError):
        chain.set_joint_placement(0, T)


def test_pinocchio_release_must_be_the_kernels(monkeypatch: pytest.MonkeyPatch) -> None:
    built = kernel.PINOCCHIO_VERSION
    assert built == pin.__version__  # this installation is consistent
    check_pinocchio(built)
    with pytest.raises(KernelError) as err:
        check_pinocchio("4.0.0", built="4.1.0")
    assert isinstance(err.value, DualArmError)
    assert "4.0.0" in str(err.value) and "4.1.0" in str(err.value)
    assert "pip install pin==4.1.0" in str(err.value)
    # The check runs when the kinematics are imported.
    monkeypatch.setattr(pin, "__version__", "3.9.0")
    with pytest.raises(KernelError, match=r"built with Pinocchio .* but Pinocchio 3\.9\.0"):
        importlib.reload(importlib.import_module("dualarm_qp.kinematics.compiled"))
    assert _compiled.REBUILD in str(err.value)


@pytest.mark.parametrize("how", ["pickle", "deepcopy"])
def test_arms_and_the_carried_object_model_pickle(how: str) -> None:
    """The kernel's copy is rebuilt from the pickled Pinocchio model.

    A deep copy too: it copies an empty array with zero strides, which the kernel's
    in-place outputs refuse, so the arm's empty Jacobian output is made again as well.
    """
    rng = np.random.default_rng(9)
    arm = puma560(base=random_pose(rng), tool=random_pose(rng, 0.1))
    carry = CarryModel(arm, CurvedBar(0.5, sigma_min=-0.2, sigma_max=0.3), random_pose(rng, 0.1))
    q = rng.uniform(-1.0, 1.0, 6)
    arm2, carry2 = (pickle.loads(pickle.dumps((arm, carry))) if how == "pickle"
                    else copy.deepcopy((arm, carry)))
    assert arm2.chain is not arm.chain
    T, J = arm.fk_jacobian(q)
    T2, J2 = arm2.fk_jacobian(q)
    np.testing.assert_array_equal(T2, T)
    np.testing.assert_array_equal(J2, J)
    np.testing.assert_array_equal(arm2.fk(q), arm.fk(q))
    np.testing.assert_array_equal(arm2.link_frames(q), arm.link_frames(q))
    kin, kin2 = carry.update(q, 0.1), carry2.update(q, 0.1)
    np.testing.assert_array_equal(kin2.T_target, kin.T_target)
    np.testing.assert_array_equal(kin2.J_target, kin.J_target)
