"""Capsules of arms: they contain every collision object of the URDF wherever the arm
moves, they sit in the frames of SerialArm.link_frames, and DH capsules join the DH
frame origins."""

from __future__ import annotations

import functools
from pathlib import Path

import coal
import numpy as np
import pinocchio as pin
import pytest
from geom_oracles import point_segment_distance

from dualarm_qp.errors import InvalidInputError
from dualarm_qp.geometry import (
    PUMA560_LINK_RADII,
    arm_capsules,
    dh_capsules,
    example_robot_capsules,
    urdf_capsules,
)
from dualarm_qp.kinematics import (
    DHTable,
    RobotModelError,
    SerialArm,
    example_robot_arm,
    puma560,
    urdf_arm,
)
from dualarm_qp.kinematics.robots import example_robot_urdf, example_robots_dir

needs_robots = pytest.mark.skipif(example_robots_dir() is None,
                                  reason="example-robot-data is not installed")

CHAINS = {
    "ur5": ("ur5", "base_link", "tool0"),
    "ur10": ("ur10", "base_link", "tool0"),
    "ur5_from_shoulder": ("ur5", "shoulder_link", "tool0"),  # a base frame off the origin
    "baxter_left": ("baxter", "left_arm_mount", "left_gripper"),
    "panda": ("panda", "panda_link0", "panda_link8"),
    "panda_primitives": ("panda_description/urdf/panda_collision.urdf", "panda_link0",
                         "panda_link8"),
}


def pose(rotvec, p):
    T = np.eye(4)
    T[:3, :3] = pin.exp3(np.asarray(rotvec, dtype=float))
    T[:3, 3] = p
    return T


@functools.cache
def capsules_of(name):
    return example_robot_capsules(*CHAINS[name])


def surface_points(geometry) -> np.ndarray:
    """Points whose convex hull is (or contains, up to 1e-3 of the radius) the geometry,
    in its own frame: a mesh's vertices, or samples of a primitive's surface."""
    if isinstance(geometry, coal.BVHModelBase):
        return np.array(geometry.vertices())
    rng = np.random.default_rng(0)
    d = rng.normal(size=(2000, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    if isinstance(geometry, coal.Sphere):
        return geometry.radius * d
    if isinstance(geometry, coal.Box):
        return np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * \
            geometry.halfSide
    if isinstance(geometry, coal.Cylinder):
        phi = np.linspace(0, 2 * np.pi, 720, endpoint=False)
        ring = np.column_stack([geometry.radius * np.cos(phi), geometry.radius * np.sin(phi)])
        h = geometry.halfLength
        return np.vstack([np.column_stack([ring, np.full(720, -h)]),
                          np.column_stack([ring, np.full(720, h)])])
    raise AssertionError(f"no sampler for {type(geometry).__name__}")


def world_points(name, arm, q):
    """Every collision object of the URDF as world points for the arm at q, with the
    index of the arm joint that moves it, from the full robot model (not our mapping)."""
    robot, root, _ = CHAINS[name]
    path = example_robot_urdf(robot)
    model = pin.buildModelFromUrdf(str(path))
    geom = pin.buildGeomFromUrdf(model, str(path), pin.GeometryType.COLLISION,
                                 package_dirs=[str(example_robots_dir().parent.parent)])
    q_full = pin.neutral(model)
    for i, joint in enumerate(arm.joint_names):
        q_full[model.joints[model.getJointId(joint)].idx_q] = q[i]
    data, gdata = model.createData(), geom.createData()
    pin.forwardKinematics(model, data, q_full)
    pin.updateFramePlacements(model, data)
    pin.updateGeometryPlacements(model, data, geom, gdata)
    root_id = model.getFrameId(root)
    to_arm = arm.base @ data.oMf[root_id].inverse().homogeneous
    names = [str(n) for n in model.names]
    out = []
    for k, obj in enumerate(geom.geometryObjects):
        key = 0
        j = obj.parentJoint
        while j > 0:
            if names[j] in arm.joint_names:
                key = arm.joint_names.index(names[j]) + 1
                break
            j = model.parents[j]
        if key == 0 and not (obj.parentJoint == model.frames[root_id].parentJoint
                             and _below(model, obj.parentFrame, root_id)):
            continue  # not on the arm
        T = to_arm @ gdata.oMg[k].homogeneous
        pts = surface_points(obj.geometry) @ T[:3, :3].T + T[:3, 3]
        out.append((obj.name, key, pts))
    return out


def _below(model, frame, ancestor):
    while frame not in (ancestor, 0):
        frame = model.frames[frame].parentFrame
    return frame == ancestor


#: Chains whose containment check runs in the full suite only (the fast loop keeps ur5
#: and panda).
SLOW_CHAINS = ("panda_primitives", "baxter_left", "ur10", "ur5_from_shoulder")


@needs_robots
@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.slow) if n in SLOW_CHAINS
                                  else n for n in CHAINS])
def test_capsules_contain_every_collision_object_as_the_arm_moves(name):
    robot, root, tip = CHAINS[name]
    rng = np.random.default_rng(11)
    arm = example_robot_arm(robot, root, tip, base=pose(rng.normal(size=3), rng.normal(size=3)))
    caps = capsules_of(name)
    assert set(caps) <= set(range(arm.n + 1))
    seen = set()
    for _ in range(3):
        q = rng.uniform(np.maximum(arm.q_min, -np.pi), np.minimum(arm.q_max, np.pi))
        frames = arm.link_frames(q)
        for obj, key, pts in world_points(name, arm, q):
            assert key in caps, f"{obj} (moved by frame {key}) has no capsule"
            seen.add(key)
            cap = caps[key].placed(frames[key])
            # a primitive's samples lie on its surface: compare with 1e-6 m of slack
            worst = max(point_segment_distance(p, cap.a, cap.b) for p in pts) - cap.radius
            assert worst <= 1e-6, f"{obj} sticks out of capsule {key} by {worst:.3g} m"
    assert seen == set(caps)


@needs_robots
@pytest.mark.parametrize("name", ["ur5", "ur10", "panda"])
def test_mesh_vertices_lie_inside_their_capsule_in_the_joint_frame(name):
    """The statement the collision limit relies on, for every mesh vertex, exactly."""
    robot, root, tip = CHAINS[name]
    arm = example_robot_arm(robot, root, tip)
    caps = capsules_of(name)
    for _, key, pts in world_points(name, arm, np.zeros(arm.n)):
        T = arm.link_frames(np.zeros(arm.n))[key]
        local = (pts - T[:3, 3]) @ T[:3, :3]
        cap = caps[key]
        d = max(point_segment_distance(p, cap.a, cap.b) for p in local)
        assert d <= cap.radius + 1e-12


@needs_robots
def test_ur5_has_one_capsule_per_link_of_plausible_size():
    caps = capsules_of("ur5")
    assert sorted(caps) == [0, 1, 2, 3, 4, 5, 6]
    # the upper arm and the forearm are the long ones (0.425 m and 0.392 m between axes)
    assert 0.40 < caps[2].length < 0.45 and 0.35 < caps[3].length < 0.41
    assert all(0.03 < c.radius < 0.1 for c in caps.values())


# ------------------------------------------------------------------ arm_capsules
@needs_robots
def test_arm_capsules_reads_the_arm_source():
    arm = example_robot_arm("ur5", "base_link", "tool0")
    by_arm = arm_capsules(arm)
    by_name = capsules_of("ur5")
    assert sorted(by_arm) == sorted(by_name)
    for key, cap in by_arm.items():
        np.testing.assert_allclose(cap.a, by_name[key].a, atol=1e-12)
        assert cap.radius == pytest.approx(by_name[key].radius, abs=1e-12)
    # a URDF read by path resolves its package:// meshes from the folders above it
    by_path = arm_capsules(urdf_arm(example_robot_urdf("ur5"), "base_link", "tool0"))
    assert sorted(by_path) == sorted(by_name)


def test_arm_capsules_of_a_dh_arm_are_dh_capsules():
    arm = puma560()
    caps = arm_capsules(arm)
    np.testing.assert_array_equal([c.radius for c in caps.values()], PUMA560_LINK_RADII)


@needs_robots
def test_arm_capsules_errors():
    arm = example_robot_arm("ur5", "base_link", "tool0")
    with pytest.raises(InvalidInputError, match="radii apply to DH arms"):
        arm_capsules(arm, radii=[0.1] * 6)
    bare = SerialArm(pin.buildModelFromUrdf(str(example_robot_urdf("ur5"))))
    assert bare.source.startswith("pinocchio:")
    with pytest.raises(InvalidInputError, match="urdf_capsules"):
        arm_capsules(bare)


@needs_robots
def test_missing_meshes_are_a_robot_model_error(tmp_path: Path):
    text = example_robot_urdf("ur5").read_text()
    urdf = tmp_path / "ur5_copy.urdf"
    urdf.write_text(text)
    with pytest.raises(RobotModelError, match="collision geometry"):
        urdf_capsules(urdf, "base_link", "tool0")
    share = example_robots_dir().parent.parent
    caps = urdf_capsules(urdf, "base_link", "tool0", package_dirs=[share])
    assert sorted(caps) == sorted(capsules_of("ur5"))


# ------------------------------------------------------------------ DH arms
def modified_arm():
    dh = DHTable([0.0, 0.1, 0.4, 0.05], np.deg2rad([0.0, -90.0, 0.0, 90.0]),
                 [0.3, 0.05, 0.0, 0.35], [0.0, 0.2, 0.0, -0.1], "modified")
    return SerialArm(dh, name="modified")


@pytest.mark.parametrize("arm", [puma560(base=pose([0.1, 0.2, 0.3], [1.0, 0.0, 0.5])),
                                 modified_arm()], ids=["puma560", "modified"])
def test_dh_capsules_join_consecutive_frame_origins_in_any_configuration(arm):
    radii = np.linspace(0.05, 0.1, arm.n)
    caps = dh_capsules(arm, radii)
    standard = arm.dh.convention == "standard"
    assert sorted(caps) == (list(range(1, arm.n + 1)) if standard else list(range(arm.n)))
    rng = np.random.default_rng(2)
    for _ in range(4):
        frames = arm.link_frames(rng.uniform(-np.pi, np.pi, arm.n))
        for i in range(1, arm.n + 1):  # segment i: origins of frames i-1 and i
            key = i if standard else i - 1
            world = caps[key].placed(frames[key])
            np.testing.assert_allclose(world.a, frames[i - 1][:3, 3], atol=1e-12)
            np.testing.assert_allclose(world.b, frames[i][:3, 3], atol=1e-12)
            assert world.radius == radii[i - 1]


def test_puma_default_radii_and_lengths():
    caps = dh_capsules(puma560())
    np.testing.assert_array_equal([caps[i].radius for i in range(1, 7)], PUMA560_LINK_RADII)
    assert caps[1].is_sphere and caps[5].is_sphere
    assert caps[2].length == pytest.approx(np.hypot(0.4318, 0.14909))
    assert caps[4].length == pytest.approx(0.43307)
    assert caps[6].length == pytest.approx(0.05625)


def test_dh_capsules_errors():
    dh = DHTable([0.0, 0.4], [0.0, 0.0], [0.2, 0.0], [0.0, 0.0])
    with pytest.raises(InvalidInputError, match="radii"):
        dh_capsules(SerialArm(dh))
    with pytest.raises(InvalidInputError, match="positive"):
        dh_capsules(SerialArm(dh), [0.1, -0.1])
    with pytest.raises(InvalidInputError, match="radii"):
        dh_capsules(SerialArm(dh), [0.1, 0.1, 0.1])


@pytest.mark.slow
@needs_robots
def test_fitted_capsules_are_kept_per_file_version(tmp_path):
    import shutil

    from dualarm_qp.geometry import links

    src = example_robot_urdf("ur5")
    first = urdf_capsules(src, "base_link", "tool0")
    again = urdf_capsules(src, "base_link", "tool0")
    assert again is not first and all(again[k] is first[k] for k in first)  # the cache
    # A copy elsewhere (with its meshes found through the original's folders) is
    # another file: fitted afresh, to the same capsules.
    copy = tmp_path / "ur5.urdf"
    shutil.copy(src, copy)
    dirs = [str(p) for p in Path(src).resolve().parents]
    fresh = urdf_capsules(copy, "base_link", "tool0", package_dirs=dirs)
    assert all(fresh[k] is not first[k] for k in first)
    assert all(np.allclose(fresh[k].a, first[k].a) for k in first)
    # Editing the file (its size or time changes) fits it again.
    copy.write_text(copy.read_text() + "\n")
    edited = urdf_capsules(copy, "base_link", "tool0", package_dirs=dirs)
    assert all(edited[k] is not fresh[k] for k in first)
    assert len(links._FITTED) <= links._FITTED_MAX
