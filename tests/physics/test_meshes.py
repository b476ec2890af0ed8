"""A URDF arm's collision geometry in MuJoCo: convex hulls placed as Pinocchio places them."""

from __future__ import annotations

from pathlib import Path

import coal
import numpy as np
import pinocchio as pin
import pytest
from scipy.spatial import ConvexHull

from dualarm_qp.errors import InvalidInputError
from dualarm_qp.experiments import build_experiment, load_config
from dualarm_qp.kinematics.robots import example_robot_urdf, example_robots_dir
from dualarm_qp.physics.meshes import hull_vertices, link_geom, mesh_xml
from dualarm_qp.physics.mjcf import build_mjcf
from dualarm_qp.physics.settings import PhysicsSettings

mujoco = pytest.importorskip("mujoco", reason="the physics check needs MuJoCo "
                                               "(pip install -e '.[physics]'; '.[dev]' has it)")

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
needs_robots = pytest.mark.skipif(
    example_robots_dir() is None,
    reason="example-robot-data is not installed (pip install -e '.[robots]'; '.[dev]' has it)")

UR5 = CONFIGS / "ur5_pair_sliding_bar.yaml"
PANDA = CONFIGS / "panda_pair.yaml"
BEAM = CONFIGS / "puma_beam_limits.yaml"  # PUMA 560 from its DH table
TOL = 1e-6  # m: MuJoCo keeps mesh vertices in single precision


def _experiment(path: Path):
    return build_experiment(load_config(path), str(path))


def _compiled(exp, geometry: str = "meshes"):
    pm = build_mjcf(exp.task, PhysicsSettings(geometry=geometry))
    return pm, mujoco.MjModel.from_xml_string(pm.xml)


def _urdf_geometry(arm):
    """The arm's URDF, read afresh: full model, its collision geometry, root frame id."""
    kind, _, rest = arm.source.partition(":")
    where, _, chain = rest.rpartition(" ")
    root = chain.partition("->")[0]
    path = example_robot_urdf(where) if kind == "example_robot" else Path(where)
    model = pin.buildModelFromUrdf(str(path))
    geom = pin.buildGeomFromUrdf(model, str(path), pin.GeometryType.COLLISION,
                                 package_dirs=[str(p) for p in path.resolve().parents])
    return model, geom, model.getFrameId(root)


def _world_points(obj, M: pin.SE3) -> np.ndarray:
    """A collision object's mesh vertices (or a box's corners) in the world."""
    g = obj.geometry
    if isinstance(g, coal.BVHModelBase):
        v = np.array(g.vertices()).reshape(-1, 3)
    elif isinstance(g, coal.Box):
        v = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
                     ) * np.array(g.halfSide)
    else:
        pytest.fail(f"no points for a {type(g).__name__} in this test")
    return v @ M.rotation.T + M.translation


def _geom_world_vertices(model, data, g: int) -> np.ndarray:
    """A MuJoCo geom's vertices in the world: a mesh's hull vertices, a box's corners."""
    if model.geom_type[g] == mujoco.mjtGeom.mjGEOM_MESH:
        mesh = model.geom_dataid[g]
        adr, n = model.mesh_vertadr[mesh], model.mesh_vertnum[mesh]
        local = np.asarray(model.mesh_vert[adr:adr + n], dtype=float)
    else:
        assert model.geom_type[g] == mujoco.mjtGeom.mjGEOM_BOX
        local = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
                         ) * model.geom_size[g]
    return local @ data.geom_xmat[g].reshape(3, 3).T + data.geom_xpos[g]


@needs_robots
@pytest.mark.parametrize("config", [UR5, PANDA], ids=["ur5", "panda"])
def test_each_collision_mesh_is_its_hull_placed_where_pinocchio_puts_it(config):
    """At random joints, every URDF vertex lies in (or on) MuJoCo's geom, whose vertices
    are URDF vertices: the hull of each collision object, placed right (to 1e-6 m)."""
    exp = _experiment(config)
    pm, model = _compiled(exp)
    data = mujoco.MjData(model)
    rng = np.random.default_rng(3)
    for role, arm in (("leader", exp.task.leader), ("follower", exp.task.follower)):
        full, geom, root = _urdf_geometry(arm)
        gdata = geom.createData()
        fdata = full.createData()
        idx = [full.idx_qs[full.getJointId(n)] for n in arm.joint_names]
        adr = [model.jnt_qposadr[model.joint(n).id] for n in pm.joints[role]]
        seen = 0
        for _ in range(4):
            q = rng.uniform(arm.q_min, arm.q_max)
            q_full = pin.neutral(full)
            q_full[idx] = q
            pin.framesForwardKinematics(full, fdata, q_full)
            pin.updateGeometryPlacements(full, fdata, geom, gdata)
            world_root = pin.SE3(np.asarray(arm.base)) * fdata.oMf[root].inverse()
            data.qpos[adr] = q
            mujoco.mj_kinematics(model, data)
            for i, obj in enumerate(geom.geometryObjects):
                g = model.geom(f"{role}_{obj.name}").id  # every object is on the chain
                urdf = _world_points(obj, world_root * gdata.oMg[i])
                mj = _geom_world_vertices(model, data, g)
                hull = ConvexHull(mj)
                outside = (urdf @ hull.equations[:, :3].T + hull.equations[:, 3]).max()
                assert outside <= TOL, (role, obj.name)
                gap = np.linalg.norm(mj[:, None, :] - urdf[None, :, :], axis=2).min(axis=1)
                assert gap.max() <= TOL, (role, obj.name)
                seen += 1
        assert seen == 4 * len(geom.geometryObjects)


@needs_robots
@pytest.mark.parametrize("config", [UR5, PANDA], ids=["ur5", "panda"])
def test_meshes_leave_the_bodies_masses_pinocchios(config):
    exp = _experiment(config)
    for geometry in ("meshes", "capsules"):
        _, model = _compiled(exp, geometry)
        for role, arm in (("leader", exp.task.leader), ("follower", exp.task.follower)):
            for j in range(1, arm.n + 1):
                body = model.body(f"{role}_link{j}").id
                assert abs(model.body_mass[body] - arm.model.inertias[j].mass) <= 1e-9
                np.testing.assert_allclose(model.body_ipos[body],
                                           arm.model.inertias[j].lever, rtol=0, atol=1e-9)


@needs_robots
def test_the_geometry_setting_picks_meshes_or_capsules_and_says_so():
    exp = _experiment(UR5)
    pm, model = _compiled(exp, "meshes")
    kinds = {model.geom_type[g] for g in range(model.ngeom)
             if model.body(model.geom_bodyid[g]).name.startswith("leader_link")}
    assert mujoco.mjtGeom.mjGEOM_MESH in kinds and model.nmesh > 0
    assert any("convex hulls" in n for n in pm.notes)
    assert "<mesh " in pm.xml and "file=" not in pm.xml  # inline, no files
    pm, model = _compiled(exp, "capsules")
    assert model.nmesh == 0 and not any("convex hulls" in n for n in pm.notes)


def test_a_dh_arm_keeps_its_capsules_under_meshes():
    exp = _experiment(BEAM)
    pm, model = _compiled(exp, "meshes")
    assert model.nmesh == 0
    assert pm.xml == build_mjcf(exp.task, PhysicsSettings(geometry="capsules")).xml
    assert any("DH arm has no collision meshes" in n for n in pm.notes)


def test_hull_vertices_are_the_hulls_corners():
    rng = np.random.default_rng(0)
    cube = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    inside = rng.uniform(0.1, 0.9, (50, 3))
    v = hull_vertices(np.vstack([inside, cube]))
    np.testing.assert_array_equal(np.sort(v, axis=0), np.sort(cube, axis=0))


def test_a_flat_mesh_is_refused_with_a_reason():
    flat = np.c_[np.random.default_rng(1).uniform(size=(20, 2)), np.zeros(20)]
    with pytest.raises(InvalidInputError, match="spans no volume"):
        hull_vertices(flat)
    mesh = coal.BVHModelOBBRSS()
    mesh.beginModel(0, 0)
    mesh.addVertices(flat)
    mesh.endModel()
    with pytest.raises(InvalidInputError, match=r"'plate'.*geometry: capsules"):
        link_geom("plate", mesh, np.eye(4))


def test_primitives_stay_primitives_and_have_no_mesh():
    T = np.eye(4)
    box = link_geom("b", coal.Box(0.2, 0.4, 0.6), T)
    assert box.kind == "box" and np.allclose(box.size, [0.1, 0.2, 0.3])
    cyl = link_geom("c", coal.Cylinder(0.05, 0.3), T)
    assert cyl.kind == "cylinder" and np.allclose(cyl.size, [0.05, 0.15])
    assert link_geom("s", coal.Sphere(0.07), T).kind == "sphere"
    with pytest.raises(InvalidInputError, match="primitive"):
        mesh_xml(box, "b")


@needs_robots
def test_a_box_inside_the_capsule_but_outside_the_hull_touches_only_the_capsule():
    """A small box obstacle inside the forearm's capsule, beyond its mesh's hull: a
    contact with capsules, none (and a positive distance) with meshes."""
    exp = _experiment(UR5)
    q = np.zeros(exp.task.leader.n)
    models = {}
    for geometry in ("meshes", "capsules"):
        pm, model = _compiled(exp, geometry)
        data = mujoco.MjData(model)
        data.qpos[[model.jnt_qposadr[model.joint(n).id] for n in pm.joints["leader"]]] = q
        mujoco.mj_kinematics(model, data)
        models[geometry] = (pm, model, data)
    _, cm, cd = models["capsules"]
    cap = _body_geoms(cm, "leader_link3")[0]
    assert cm.geom_type[cap] == mujoco.mjtGeom.mjGEOM_CAPSULE
    r = float(cm.geom_size[cap][0])
    centre, axis = cd.geom_xpos[cap], cd.geom_xmat[cap].reshape(3, 3)[:, 2]
    _, mm, md = models["meshes"]
    hull = np.vstack([_geom_world_vertices(mm, md, g) for g in _body_geoms(mm, "leader_link3")])
    # the side of the capsule farthest from the hull
    e1 = np.cross(axis, [1.0, 0.0, 0.0] if abs(axis[0]) < 0.9 else [0.0, 1.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(axis, e1)
    sides = [np.cos(a) * e1 + np.sin(a) * e2 for a in np.linspace(0, 2 * np.pi, 72, False)]
    n = min(sides, key=lambda s: ((hull - centre) @ s).max())
    support = float(((hull - centre) @ n).max())
    assert support < r - 0.007, "the capsule should stand off the forearm's mesh somewhere"
    box_centre = centre + (r - 0.003) * n  # 2 mm cube: from r - 5 mm to r - 1 mm
    R = np.column_stack([n, e1 if abs(n @ e1) < 0.9 else e2, axis])
    R[:, 1] -= R[:, 0] * (R[:, 0] @ R[:, 1])
    R[:, 1] /= np.linalg.norm(R[:, 1])
    R[:, 2] = np.cross(R[:, 0], R[:, 1])
    quat = np.empty(4)
    mujoco.mju_mat2Quat(quat, R.ravel())
    touching = {}
    for geometry, (pm, _, _) in models.items():
        spec = mujoco.MjSpec.from_string(pm.xml)
        spec.worldbody.add_geom(name="probe", type=mujoco.mjtGeom.mjGEOM_BOX,
                                size=[0.002] * 3, pos=box_centre, quat=quat,
                                contype=0, conaffinity=1)
        model = spec.compile()
        data = mujoco.MjData(model)
        data.qpos[[model.jnt_qposadr[model.joint(n).id] for n in pm.joints["leader"]]] = q
        mujoco.mj_forward(model, data)
        probe, link = model.geom("probe").id, _body_geoms(model, "leader_link3")
        touching[geometry] = [c.dist for c in data.contact[:data.ncon]
                              if probe in c.geom and set(c.geom) & set(link)]
        if geometry == "meshes":
            distance = min(mujoco.mj_geomDistance(model, data, probe, g, 0.1, None)
                           for g in link)
            assert distance > 0.001
    assert touching["meshes"] == []
    assert len(touching["capsules"]) >= 1 and min(touching["capsules"]) < 0


def _body_geoms(model, body: str) -> list[int]:
    b = model.body(body).id
    return [g for g in range(model.ngeom) if model.geom_bodyid[g] == b]
