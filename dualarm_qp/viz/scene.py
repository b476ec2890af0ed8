"""What the 3D view draws of a task: arm links, joint markers, the object and the path D(t).

The scene is described once, as plain numbers (a JSON-ready dict), and the browser page
builds it with three.js. Every part hangs off a *node* whose world pose changes over
time: node ``i`` of an arm is its frame ``i`` (:meth:`~dualarm_qp.kinematics.SerialArm.
link_frames`, frame 0 the base) and the last node its tool frame; the object's node is
the object frame ``T_world_object = leader.fk(q_l) @ H1`` (``H1(sigma_l)`` when the
leader's grasp slides). A part's pose in its node is
constant, so a frame of the animation only moves nodes (see :mod:`.frames`).

An arm built from a URDF is drawn with the visual meshes (and boxes, cylinders, spheres)
of its links, each fixed in the node of the joint that moves it (:mod:`.meshes`); the
meshes are stored once per scene, in ``scene["meshes"]``, however many parts draw them.
Any other arm (a DH table), or a URDF arm some of whose meshes cannot be read, is drawn
as a cylinder per link between consecutive frame origins (a *capsule*), with a sphere at
each frame origin. Every arm has a short cylinder along each joint axis that changes
colour when the joint nears or leaves its range (drawn over the meshes, so that they do
not hide it; on such an arm the page shows only those of joints near or outside their
range until asked for all). The object is a bar along the grasp path
(boxes following the path, or a cylinder for a :class:`~dualarm_qp.task.surfaces.
CylinderSurface`), with the grasp range as a green strip on the grasp surface. A task
with a collision scene adds its obstacles and, on a toggle, the collision shapes of the
links and the object (:mod:`.collision`).
"""

from __future__ import annotations

import itertools
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..kinematics.arm import SerialArm
from ..task.scene import DualArmTask
from ..task.surfaces import CurvedBar, CylinderSurface, GraspSurface
from .collision import collision_parts
from .meshes import MeshLibrary, arm_visuals

FloatArray = NDArray[np.float64]

#: Colours of the two arms, the object, the grasp range and the path (``#rrggbb``).
COLOURS = {"leader": "#3b6fb6", "follower": "#c9832f", "object": "#9a9a9a",
           "range": "#2ca02c", "grasp": "#d62728", "path": "#7b2cbf"}

#: Radius of a link cylinder [m] and of a frame-origin sphere [m].
LINK_RADIUS, FRAME_RADIUS = 0.025, 0.032
#: Joint-axis marker: radius and length [m].
JOINT_RADIUS, JOINT_LENGTH = 0.04, 0.09
#: Joint-axis marker of an arm drawn with meshes, over them: a thin rod [m].
MESH_JOINT_RADIUS, MESH_JOINT_LENGTH = 0.014, 0.22
#: Bar cross-section: width along n* and depth behind the surface along -a* [m].
BAR_WIDTH, BAR_DEPTH = 0.05, 0.025
#: The grasp marker (a ball): its radius against the bar's width or the cylinder's
#: diameter, and against the length of the object drawn.
GRASP_PER_WIDTH, GRASP_PER_LENGTH = 0.6, 0.03
#: Samples of D(t) drawn as the path line.
PATH_SAMPLES = 200


def _pose_list(T: FloatArray) -> list[float]:
    """Return a 4x4 pose as 16 numbers, column-major (three.js ``Matrix4.fromArray``)."""
    return [round(float(x), 7) for x in np.asarray(T, dtype=float).T.ravel()]


def _frame_with_z(origin: FloatArray, axis: FloatArray) -> FloatArray:
    """Return a pose at ``origin`` with local y along ``axis`` (three.js cylinders lie on y)."""
    y = axis / np.linalg.norm(axis)
    helper = np.array([1.0, 0.0, 0.0]) if abs(y[0]) < 0.9 else np.array([0.0, 0.0, 1.0])
    x = np.cross(y, helper)
    x /= np.linalg.norm(x)
    z = np.cross(x, y)
    T = np.eye(4)
    T[:3, :3] = np.column_stack([x, y, z])
    T[:3, 3] = origin
    return T


def arm_node_poses(arm: SerialArm, q: Any) -> FloatArray:
    """World poses of an arm's nodes: frames 0..n then the tool, shape (n + 2, 4, 4) [m]."""
    return np.concatenate([arm.link_frames(q), arm.fk(q)[None]], axis=0)


def _sample_q(arm: SerialArm, rng: np.random.Generator) -> FloatArray:
    lo = np.where(np.isfinite(arm.q_min), arm.q_min, -np.pi)
    hi = np.where(np.isfinite(arm.q_max), arm.q_max, np.pi)
    return rng.uniform(lo, hi)


def _local(T_node: FloatArray, p_world: FloatArray) -> FloatArray:
    return np.linalg.solve(T_node, np.append(p_world, 1.0))[:3]


def arm_parts(arm: SerialArm, role: str, library: MeshLibrary | None = None
              ) -> dict[str, Any]:
    """Describe an arm's links and joint markers, each fixed in one node.

    With a ``library``, an arm built from a URDF is drawn with its links' visuals
    (:func:`~dualarm_qp.viz.meshes.arm_visuals`). Otherwise, and when some of those
    cannot be read, capsules are drawn: a link between nodes ``k`` and ``k + 1`` is
    fixed in whichever of the two keeps it constant (the parent for a URDF chain, the
    child for a DH table), found by evaluating two random configurations, so it holds
    for any model.

    Parameters
    ----------
    arm : SerialArm
        The arm.
    role : str
        ``"leader"`` or ``"follower"`` (its colour).
    library : MeshLibrary, optional
        Where the meshes of a URDF arm go (one per scene); None draws capsules only.

    Returns
    -------
    dict
        ``nodes`` (count), ``parts`` (meshes, boxes, cylinders and spheres with ``node``
        and a column-major local ``pose`` [m]; a mesh part has ``mesh``, its index in
        the library, and ``scale``), ``joints`` (one marker per joint), ``colour``,
        ``joint_names``, ``drawn`` (``"meshes"``, ``"capsules"`` or ``"meshes and
        capsules"``) and ``notes`` (what could not be drawn, for the page's readout).
    """
    rng = np.random.default_rng(0)
    qa, qb = _sample_q(arm, rng), _sample_q(arm, rng)
    Ta, Tb = arm_node_poses(arm, qa), arm_node_poses(arm, qb)
    nodes = len(Ta)
    visuals = arm_visuals(arm, library) if library is not None else None
    notes: list[str] = []
    meshes = []
    if visuals is not None:
        meshes = [{**p, "pose": _pose_list(p["pose"])} for p in visuals.parts]
        if visuals.missing:
            shown = "; ".join(visuals.missing[:3])
            more = f" and {len(visuals.missing) - 3} more" if len(visuals.missing) > 3 else ""
            notes.append(f"{role}: {len(visuals.missing)} visual(s) not drawn ({shown}{more}); "
                         "links drawn as capsules")
        elif not meshes:
            notes.append(f"{role}: its URDF links have no visuals; links drawn as capsules")
    with_capsules = not meshes or bool(notes)
    joints = _joint_markers(arm, qa, Ta, *((MESH_JOINT_RADIUS, MESH_JOINT_LENGTH) if meshes
                                           else (JOINT_RADIUS, JOINT_LENGTH)))
    drawn = "capsules" if not meshes else "meshes and capsules" if with_capsules else "meshes"
    return {"name": role, "nodes": nodes,
            "parts": meshes + (_capsules(Ta, Tb) if with_capsules else []),
            "joints": joints, "colour": COLOURS[role], "drawn": drawn, "notes": notes,
            "markers_on_top": bool(meshes),
            "joint_names": [f"q{j + 1}" for j in range(arm.n)]}


def _capsules(Ta: FloatArray, Tb: FloatArray) -> list[dict[str, Any]]:
    """Frame spheres and link cylinders, from the node poses of two configurations."""
    nodes = len(Ta)
    parts: list[dict[str, Any]] = []
    for k in range(nodes):
        parts.append({"node": k, "shape": "sphere", "radius": FRAME_RADIUS,
                      "pose": _pose_list(np.eye(4))})
    for k in range(nodes - 1):
        length = float(np.linalg.norm(Ta[k + 1][:3, 3] - Ta[k][:3, 3]))
        if length < 1e-6:
            continue
        in_parent = (_local(Ta[k], Ta[k + 1][:3, 3]), _local(Tb[k], Tb[k + 1][:3, 3]))
        in_child = (_local(Ta[k + 1], Ta[k][:3, 3]), _local(Tb[k + 1], Tb[k][:3, 3]))
        if np.allclose(*in_parent, atol=1e-9):
            node, tip = k, in_parent[0]
        else:
            node, tip = k + 1, in_child[0]
        T = _frame_with_z(tip / 2.0, tip)
        parts.append({"node": node, "shape": "cylinder", "radius": LINK_RADIUS,
                      "length": length, "pose": _pose_list(T)})
    return parts


def _joint_markers(arm: SerialArm, qa: FloatArray, Ta: FloatArray, radius: float,
                   length: float) -> list[dict[str, Any]]:
    """One marker per joint, along its axis, fixed in a node that keeps it constant [m]."""
    joints = []
    for j in range(arm.n):
        moved = j + 1  # frame j + 1 is the first that joint j turns
        node = j if arm.dh is not None else moved  # DH: joint j turns about z of frame j
        dq = np.zeros(arm.n)
        dq[j] = 1e-6
        w = arm_node_poses(arm, qa + dq)[moved][:3, :3] @ Ta[moved][:3, :3].T
        axis_world = np.array([w[2, 1] - w[1, 2], w[0, 2] - w[2, 0], w[1, 0] - w[0, 1]])
        if np.linalg.norm(axis_world) < 1e-12:
            axis_world = Ta[node][:3, 2]
        axis_local = Ta[node][:3, :3].T @ axis_world
        joints.append({"node": node, "radius": radius, "length": length,
                       "pose": _pose_list(_frame_with_z(np.zeros(3), axis_local))})
    return joints


def _box(p0: FloatArray, p1: FloatArray, R: FloatArray, width: float, depth: float,
         lift: float) -> dict[str, Any]:
    """Return a box from ``p0`` to ``p1`` (on s*), ``width`` on n*, ``depth`` on a*."""
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = 0.5 * (p0 + p1) + R[:, 2] * lift
    return {"shape": "box", "size": [float(np.linalg.norm(p1 - p0)), width, depth],
            "pose": _pose_list(T)}


def _strip(surface: GraspSurface, lo: float, hi: float, *, width: float, depth: float,
           lift: float) -> list[dict[str, Any]]:
    """Boxes following the grasp path from ``lo`` to ``hi`` [m] (one when it is straight)."""
    turns = np.linalg.norm(surface.angular_rate(0.5 * (lo + hi))) > 0.0
    sig = np.linspace(lo, hi, 33 if turns else 2)
    return [_box(surface.point(a), surface.point(b), surface.frame(0.5 * (a + b)), width,
                 depth, lift) for a, b in itertools.pairwise(sig)]


def object_parts(surface: GraspSurface, grasps: FloatArray | None = None) -> dict[str, Any]:
    """Describe the object (in object coordinates): the bar, the grasp range, the grasp.

    Parameters
    ----------
    surface : GraspSurface
        The grasp surface and path.
    grasps : ndarray, optional
        Grasp values to be shown [m]: the bar is drawn long enough to hold them.

    Returns
    -------
    dict
        ``parts`` (the bar), ``range`` (the grasp range strip), ``colour`` and
        ``grasp_radius`` [m]: the grasp marker's, scaled to the object (wider than its
        cross-section, and a few percent of its length), so that it shows beside the
        gripper that holds it.
    """
    s_origin = surface.sigma_of(np.zeros(3))
    values = [surface.sigma_min, surface.sigma_max, s_origin]
    if grasps is not None and len(grasps):
        values += [float(np.min(grasps)), float(np.max(grasps))]
    if isinstance(surface, CurvedBar):
        limit = 0.95 * np.pi * float(surface.radius)  # an arc: stay below half a turn
        values = [min(max(v, -limit), limit) for v in values]
    lo, hi = min(values) - 0.03, max(values) + 0.03
    if isinstance(surface, CylinderSurface):
        T = _frame_with_z(np.array([0.0, 0.0, 0.5 * (lo + hi)]), np.array([0.0, 0.0, 1.0]))
        bar = [{"shape": "cylinder", "radius": surface.radius, "length": hi - lo,
                "pose": _pose_list(T)}]
        width = 2.0 * float(surface.radius)
    else:
        bar = _strip(surface, lo, hi, width=BAR_WIDTH, depth=BAR_DEPTH, lift=-BAR_DEPTH / 2)
        width = BAR_WIDTH
    grasp_radius = max(GRASP_PER_WIDTH * width, GRASP_PER_LENGTH * (hi - lo))
    marks = _strip(surface, surface.sigma_min, surface.sigma_max, width=0.3 * BAR_WIDTH,
                   depth=0.004, lift=0.002)
    return {"parts": bar, "range": marks, "colour": COLOURS["object"],
            "range_colour": COLOURS["range"], "grasp_colour": COLOURS["grasp"],
            "grasp_radius": round(grasp_radius, 6)}


def path_points(task: DualArmTask, t_start: float, t_end: float) -> list[list[float]]:
    """Positions of the object path ``D(t)`` for ``t`` in ``[t_start, t_end]`` [m]."""
    if not t_end > t_start:
        t_start, t_end = task.trajectory.t0, task.trajectory.tf
    ts = np.linspace(t_start, t_end, PATH_SAMPLES)
    return [[round(float(x), 6) for x in task.trajectory.pose(float(t))[:3, 3]] for t in ts]


def describe_scene(task: DualArmTask, *, t_start: float, t_end: float,
                   grasps: FloatArray | None = None, title: str = "") -> dict[str, Any]:
    """Return the whole static scene of a task as a JSON-ready dict.

    Parameters
    ----------
    task : DualArmTask
        Arms, object, surface and path.
    t_start, t_end : float
        Path time span [s] drawn as the path line (the trajectory's own span if empty).
    grasps : ndarray, optional
        Grasp values shown [m] (the bar is drawn long enough to hold them).
    title : str
        Shown at the top of the page.

    Returns
    -------
    dict
        ``title``, ``arms`` (:func:`arm_parts`), ``meshes`` (the triangle buffers the
        arms' mesh parts index, :meth:`~dualarm_qp.viz.meshes.MeshLibrary.payload`),
        ``notes`` (what could not be drawn), ``object``, ``path``, ``path_colour``, and
        ``all_joint_axes``: whether the page starts showing the marker of every joint
        (capsule arms: they are the joints of the stick figure) or only of those near
        or outside their range (an arm drawn with meshes: the meshes show the joints,
        and a rod out of each would hide them); the page has a toggle. ``collision``:
        the obstacles and the collision shapes of a task with a collision scene
        (:func:`~dualarm_qp.viz.collision.collision_parts`), None without one.
    """
    library = MeshLibrary()
    leader = arm_parts(task.leader, "leader", library)
    follower = arm_parts(task.follower, "follower", library)
    _drop_shared_base_parts(leader, task.leader.base, follower, task.follower.base)
    return {"title": title, "arms": [leader, follower], "meshes": library.payload(),
            "notes": leader["notes"] + follower["notes"],
            "all_joint_axes": not (leader["markers_on_top"] or follower["markers_on_top"]),
            "object": object_parts(task.surface, grasps),
            "path": path_points(task, t_start, t_end),
            "path_colour": COLOURS["path"],
            "collision": collision_parts(task.scene)}


def _drop_shared_base_parts(leader: dict[str, Any], T_world_leader: FloatArray,
                            follower: dict[str, Any], T_world_follower: FloatArray) -> None:
    """Leave out the follower's base-fixed meshes that the leader draws at the same place.

    Two chains of one robot (Baxter's arms) share the links before their first joints
    (the torso): drawn once, not twice in two colours.
    """
    def world(part: dict[str, Any], T_world_base: FloatArray) -> FloatArray:
        return T_world_base @ np.array(part["pose"]).reshape(4, 4).T

    def base_mesh(part: dict[str, Any]) -> bool:
        return bool(part["node"] == 0 and part["shape"] == "mesh")

    drawn = [((p["mesh"], p["scale"]), world(p, T_world_leader))
             for p in leader["parts"] if base_mesh(p)]

    def shared(part: dict[str, Any]) -> bool:
        if not base_mesh(part):
            return False
        T = world(part, T_world_follower)
        return any(key == (part["mesh"], part["scale"]) and np.allclose(T, D, atol=1e-6)
                   for key, D in drawn)

    follower["parts"] = [p for p in follower["parts"] if not shared(p)]
