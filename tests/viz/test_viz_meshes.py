"""URDF arms are drawn with their links' meshes, placed where Pinocchio puts them."""

from __future__ import annotations

import base64
import json
import re

import numpy as np
import pinocchio as pin
import pytest

from dualarm_qp.kinematics import urdf_arm
from dualarm_qp.kinematics.robots import example_robot_arm, example_robots_dir
from dualarm_qp.viz.animation import animation_html
from dualarm_qp.viz.frames import read_timeline
from dualarm_qp.viz.mesh_files import MeshLibrary, read_mesh, read_stl
from dualarm_qp.viz.meshes import place_visuals, urdf_of
from dualarm_qp.viz.page import _inline, viewer_bundle
from dualarm_qp.viz.scene import arm_node_poses, arm_parts, describe_scene

ROBOTS = example_robots_dir()
needs_robots = pytest.mark.skipif(ROBOTS is None, reason="example-robot-data is not "
                                  "installed (pip install 'dualarm-qp[robots]')")

UR5_MESHES = ["base.dae", "shoulder.dae", "upperarm.dae", "forearm.dae", "wrist1.dae",
              "wrist2.dae", "wrist3.dae"]


def _matrix(pose16):
    return np.array(pose16).reshape(4, 4).T  # column-major, as three.js reads it


def _positions(entry):
    return np.frombuffer(base64.b64decode(entry["positions"]), dtype="<f4").reshape(-1, 3)


def _indices(entry):
    dtype = "<u2" if entry["index_bytes"] == 2 else "<u4"
    return np.frombuffer(base64.b64decode(entry["indices"]), dtype=dtype).reshape(-1, 3)


@needs_robots
def test_a_ur5_arm_has_one_mesh_per_link_on_the_joint_that_turns_it():
    library = MeshLibrary()
    parts = arm_parts(example_robot_arm("ur5", "base_link", "tool0"), "leader", library)
    meshes = [p for p in parts["parts"] if p["shape"] == "mesh"]
    payload = library.payload()
    assert parts["drawn"] == "meshes" and parts["notes"] == []
    assert [payload[p["mesh"]]["name"] for p in meshes] == UR5_MESHES
    assert [p["node"] for p in meshes] == [0, 1, 2, 3, 4, 5, 6]  # the base, then joint k
    assert len(parts["parts"]) == 7  # no capsules
    assert parts["markers_on_top"] and len(parts["joints"]) == 6


@needs_robots
def test_two_arms_of_one_model_share_their_meshes(ur5_pair):
    scene = describe_scene(ur5_pair.task, t_start=0.0, t_end=1.0)
    assert [m["name"] for m in scene["meshes"]] == UR5_MESHES
    for arm in scene["arms"]:
        assert sorted(p["mesh"] for p in arm["parts"]) == list(range(7))
    for entry in scene["meshes"]:
        positions, triangles = _positions(entry), _indices(entry)
        assert len(positions) == entry["vertices"] and len(triangles) == entry["triangles"]
        assert triangles.max() < len(positions)


def _pinocchio_oracle(arm, q):
    """World pose of every visual of the URDF, by (link, k), from Pinocchio's geometry."""
    path, root, _ = urdf_of(arm)
    full = pin.buildModelFromUrdf(str(path))
    geom = pin.buildGeomFromUrdf(full, str(path), pin.GeometryType.VISUAL,
                                 package_dirs=[str(ROBOTS.parent.parent)])
    q_full = pin.neutral(full)
    for k, name in enumerate(arm.joint_names):
        q_full[full.joints[full.getJointId(name)].idx_q] = q[k]
    data, gdata = full.createData(), geom.createData()
    pin.forwardKinematics(full, data, q_full)
    pin.updateFramePlacements(full, data)
    pin.updateGeometryPlacements(full, data, geom, gdata, q_full)
    T_world_urdf = arm.base @ data.oMf[full.getFrameId(root)].inverse().homogeneous
    out = {}
    for g, obj in enumerate(geom.geometryObjects):
        link = full.frames[obj.parentFrame].name
        k = sum(key[0] == link for key in out)
        vertices = np.asarray(obj.geometry.vertices()) * obj.meshScale
        out[link, k] = (T_world_urdf @ gdata.oMg[g].homogeneous, vertices)
    return out


@needs_robots
@pytest.mark.parametrize(("robot", "root", "tip", "links"), [
    ("ur5", "base_link", "tool0", 7),
    ("panda", "panda_link0", "panda_link8", 11),  # the hand and fingers follow joint 7
])
@pytest.mark.slow
def test_mesh_vertices_are_where_pinocchio_places_the_visual_geometry(robot, root, tip, links):
    base = np.eye(4)
    base[:3, :3] = pin.rpy.rpyToMatrix(0.1, -0.2, 2.5)
    base[:3, 3] = [1.2, -0.3, 0.4]
    arm = example_robot_arm(robot, root, tip, base=base)
    library = MeshLibrary()
    parts = arm_parts(arm, "follower", library)
    payload = library.payload()
    rng = np.random.default_rng(7)
    q = rng.uniform(np.maximum(arm.q_min, -3.0), np.minimum(arm.q_max, 3.0))
    oracle = _pinocchio_oracle(arm, q)
    nodes = arm_node_poses(arm, q)
    seen: dict[str, int] = {}
    meshes = [p for p in parts["parts"] if p["shape"] == "mesh"]
    assert len(meshes) == links
    for part in meshes:
        k = seen.get(part["link"], 0)
        seen[part["link"]] = k + 1
        T_world_expected, vertices = oracle[part["link"], k]
        T_world_part = nodes[part["node"]] @ _matrix(part["pose"])
        ours = _positions(payload[part["mesh"]]) * part["scale"]
        np.testing.assert_allclose(ours, vertices, atol=1e-6)  # the same mesh, as float32
        ours_world = ours @ T_world_part[:3, :3].T + T_world_part[:3, 3]
        expected = vertices @ T_world_expected[:3, :3].T + T_world_expected[:3, 3]
        np.testing.assert_allclose(ours_world, expected, atol=1e-6)


@needs_robots
def test_one_chain_of_a_two_armed_robot_draws_its_own_links_only():
    left = place_visuals(example_robot_arm("baxter", "base", "left_gripper"))
    links = {p.visual.link for p in left}
    assert "torso" in links  # on the way from the root to the first joint: the base
    assert {p.node for p in left if p.visual.link == "torso"} == {0}
    assert not any(name.startswith(("right_", "r_gripper", "head", "pedestal", "screen"))
                   for name in links)
    hand = {p.visual.link: p.node for p in left if "gripper" in p.visual.link}
    assert hand and set(hand.values()) == {7}  # after the tip: fixed to the last joint


def test_a_dh_arm_is_drawn_with_capsules(beam):
    library = MeshLibrary()
    parts = arm_parts(beam.task.leader, "leader", library)
    assert urdf_of(beam.task.leader) is None
    assert parts["drawn"] == "capsules" and len(library) == 0
    shapes = {p["shape"] for p in parts["parts"]}
    assert shapes == {"sphere", "cylinder"} and not parts["markers_on_top"]
    scene = describe_scene(beam.task, t_start=0.0, t_end=1.0)
    assert scene["meshes"] == [] and scene["notes"] == []


def _stl_binary(path, triangles):
    record = np.dtype([("normal", "<f4", 3), ("corners", "<f4", (3, 3)), ("attr", "<u2")])
    rows = np.zeros(len(triangles), dtype=record)
    rows["corners"] = triangles
    path.write_bytes(b"\0" * 80 + np.uint32(len(rows)).tobytes() + rows.tobytes())


TETRA = np.array([[[0, 0, 0], [0.1, 0, 0], [0, 0.1, 0]], [[0, 0, 0], [0, 0.1, 0], [0, 0, 0.1]],
                  [[0, 0, 0], [0, 0, 0.1], [0.1, 0, 0]], [[0.1, 0, 0], [0, 0, 0.1], [0, 0.1, 0]]])


def test_binary_and_ascii_stl_give_the_same_shared_mesh(tmp_path):
    _stl_binary(tmp_path / "b.stl", TETRA)
    facets = "".join("facet normal 0 0 0\n outer loop\n" + "".join(
        f"  vertex {x} {y} {z}\n" for x, y, z in tri) + " endloop\nendfacet\n" for tri in TETRA)
    (tmp_path / "a.stl").write_text(f"solid t\n{facets}endsolid t\n")
    for name in ("a.stl", "b.stl"):
        vertices, triangles = read_stl(tmp_path / name)
        assert vertices.shape == (4, 3) and triangles.shape == (4, 3)
        np.testing.assert_allclose(vertices[triangles], TETRA, atol=1e-7)


@needs_robots
def test_our_stl_reader_agrees_with_coal():
    path = ROBOTS / "ur_description/meshes/ur5/collision/forearm.stl"
    ours, tris = read_stl(path)
    coal = pytest.importorskip("coal")
    theirs = np.asarray(coal.MeshLoader().load(str(path), np.ones(3)).vertices())
    sort = np.lexsort(ours.T[::-1])
    np.testing.assert_allclose(ours[sort], np.unique(theirs, axis=0), atol=1e-9)
    assert tris.shape[0] > 100 and read_mesh(path)[0].shape == ours.shape


URDF = """<robot name="twolink">
  <link name="base"><visual><geometry><mesh filename="{missing}"/></geometry></visual></link>
  <link name="upper">
    <visual><origin xyz="0 0 0.2"/><geometry><mesh filename="tetra.stl" scale="2 2 2"/>
    </geometry></visual>
    <visual><geometry><mesh filename="broken.dae"/></geometry></visual>
    <visual><origin xyz="0 0 0.1"/><geometry><cylinder radius="0.03" length="0.2"/>
    </geometry></visual>
  </link>
  <link name="tip"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="upper"/>
    <axis xyz="0 0 1"/><limit lower="-2" upper="2" effort="1" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="upper"/><child link="tip"/>
    <origin xyz="0 0 0.4"/><axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="1"
    velocity="1"/></joint>
</robot>"""


def test_missing_or_broken_meshes_fall_back_to_capsules_with_a_note(tmp_path):
    _stl_binary(tmp_path / "tetra.stl", TETRA)
    (tmp_path / "broken.dae").write_text("not a collada file")
    (tmp_path / "arm.urdf").write_text(URDF.format(missing="package://nowhere/base.stl"))
    arm = urdf_arm(tmp_path / "arm.urdf", "base", "tip")
    library = MeshLibrary()
    parts = arm_parts(arm, "leader", library)
    assert parts["drawn"] == "meshes and capsules"
    assert len(parts["notes"]) == 1 and "2 visual(s) not drawn" in parts["notes"][0]
    assert "base.stl" in parts["notes"][0] and "broken.dae" in parts["notes"][0]
    mesh = [p for p in parts["parts"] if p["shape"] == "mesh"]
    assert [(p["link"], p["node"], p["scale"]) for p in mesh] == [("upper", 1, [2.0, 2, 2])]
    np.testing.assert_allclose(_matrix(mesh[0]["pose"])[:3, 3], [0, 0, 0.2])
    rod = [p for p in parts["parts"] if p.get("link") == "upper" and p["shape"] == "cylinder"]
    assert len(rod) == 1 and rod[0]["length"] == 0.2  # turned so that its y lies on URDF z
    np.testing.assert_allclose(_matrix(rod[0]["pose"])[:3, 1], [0, 0, 1], atol=1e-12)
    capsules = [p for p in parts["parts"] if "link" not in p and p["shape"] == "cylinder"]
    assert capsules  # the whole arm is still drawn


def test_the_notes_reach_the_page(beam, run_dir, tmp_path):
    """A task whose leader's meshes are missing still gives a page, which says so."""
    (tmp_path / "arm.urdf").write_text(URDF.format(missing="gone.stl"))
    (tmp_path / "broken.dae").write_text("")
    leader = urdf_arm(tmp_path / "arm.urdf", "base", "tip")
    scene = describe_scene(_with_leader(beam.task, leader), t_start=0.0, t_end=1.0)
    assert any("gone.stl" in note for note in scene["notes"])
    timeline = read_timeline(run_dir / "trajectory.csv")
    assert timeline.q_l.shape[1] == 6  # the beam's leader: a page needs a 2-joint timeline
    short = type(timeline)(t=timeline.t[:3], path_t=timeline.path_t[:3],
                           q_l=np.zeros((3, 2)), q_f=timeline.q_f[:3],
                           grasp=timeline.grasp[:3], status=timeline.status[:3], scale=None)
    page = animation_html(_with_leader(beam.task, leader), short)
    data = json.loads(re.search(r'id="dualarm-data" type="application/json">(.*?)</script>',
                                page, re.S).group(1))
    assert any("gone.stl" in note for note in data["scene"]["notes"])
    assert 'id="notes"' in page


def _with_leader(task, leader):
    import dataclasses

    return dataclasses.replace(task, leader=leader)


@needs_robots
def test_a_page_with_meshes_stays_self_contained(ur5_run_dir):
    page = (ur5_run_dir / "animation.html").read_text()
    data = re.search(r'id="dualarm-data" type="application/json">(.*?)</script>', page, re.S)
    payload = json.loads(data.group(1))
    assert len(payload["scene"]["meshes"]) == 7
    assert "://" not in data.group(1)  # no package://, file:// or http(s):// address
    bundle = _inline(viewer_bundle())
    assert bundle in page
    assert not re.search(r"https?://", page.replace(bundle, ""))  # the viewer's own aside
    assert not re.search(r"<(script|img|link|iframe)[^>]*\s(src|href)=", page, re.I)
    assert "connect-src 'none'" in page
    assert len(page) < 6_000_000


@needs_robots
def test_the_live_view_draws_the_same_meshes(ur5_pair):
    from dualarm_qp.viz import LiveView

    with LiveView(ur5_pair.task, open_browser=False) as view:
        data = re.search(r'id="dualarm-data" type="application/json">(.*?)</script>',
                         view.page, re.S)
        scene = json.loads(data.group(1))["scene"]
    assert [m["name"] for m in scene["meshes"]] == UR5_MESHES
    assert {a["drawn"] for a in scene["arms"]} == {"meshes"}
