"""An MJCF model of a task: both arms, the carried object, the grasps and the obstacles.

* **Arms** come from their Pinocchio models (:attr:`SerialArm.model
  <dualarm_qp.kinematics.SerialArm.model>`, base placement included): one body per
  joint, placed by the joint's placement, turning about the joint's axis, so that the
  MJCF's kinematics are Pinocchio's (the DH table's or the URDF's). A link's mass and
  inertia are the model's; a link whose model has none is given the mass of its
  capsules at :attr:`PhysicsSettings.link_density` (MuJoCo computes their inertia).
  The geometry only matters for contacts: a URDF arm's is its collision geometry
  (:mod:`dualarm_qp.physics.meshes`: meshes as their convex hulls, given inline, and
  primitives) under ``geometry: meshes``, the default; a DH arm's, and any arm's
  under ``geometry: capsules``, the project's per-link capsules
  (:mod:`dualarm_qp.geometry.links`, or the collision scene's when the task has one).
* The **object** is a free body with its mass (the file's, else
  :attr:`PhysicsSettings.object_mass`) at its mass centre; its shape is the file's, else
  a 20 mm capsule from the leader's hand to the far end of the follower's range.
* The **leader's grasp** is a weld between its tool frame and the object (a sliding
  leader grasp is a slide chain, as the follower's).
* The **follower's grasp** is a frictionless slide: a chain of bodies under the object
  whose joints are the sliding path (:meth:`GraspSurface.slide_joint
  <dualarm_qp.task.surfaces.GraspSurface.slide_joint>`: a slide along a straight path,
  a hinge about the centre of a circular one) and the free spin about the sliding axis,
  its end welded to the follower's tool. A **support** (Case 2) is a chain that leaves
  every motion free but one: the hand's motion into the object along the normal, a
  one-sided joint limit (the hand pushes, never pulls).
* **Obstacles** are the collision scene's, fixed in the world.
* A **force/torque sensor** at each tool frame (site ``<role>_ft``, sensors
  ``<role>_force`` and ``<role>_torque``), between the arm's last link and its tool
  body (:data:`CHAIN_MASS`), as a wrist sensor between a robot's flange and its hand
  (:mod:`dualarm_qp.physics.sensors` reads them).

Nothing here imports MuJoCo: the model is text (:func:`build_mjcf`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from ..geometry.shapes import Box, Capsule
from ..kinematics.arm import SerialArm
from ..task.scene import DualArmTask
from ..task.surfaces import GraspSurface
from .meshes import LinkGeom, geom_xml, link_shapes, mesh_xml
from .settings import SUBSTEP, PhysicsSettings

FloatArray = NDArray[np.float64]

#: Radius [m] of the default object.
OBJECT_RADIUS = 0.02
#: Mass [kg] and inertia [kg m^2] of each arm's tool body and of the bodies of a grasp
#: chain (nearly massless).
CHAIN_MASS, CHAIN_INERTIA = 0.1, 1e-4
#: Inertia [kg m^2] of a grasp chain's bodies: MuJoCo sets a weld's stiffness from the
#: inertia of the bodies it joins, and a chain's spin joint with :data:`CHAIN_INERTIA`
#: made the follower's weld turn 15 times as far as the leader's under one moment.
CHAIN_BODY_INERTIA = 1e-2
#: Weld and joint-limit stiffness: MuJoCo's ``solref`` time constant [s] and damping ratio.
SOLREF = (2 * SUBSTEP, 1.0)
#: How many bodies at the tip of each arm never touch the object (the grasping wrist).
WRIST_BODIES = 3
#: Standard gravity [m/s^2] when the task states none.
GRAVITY = (0.0, 0.0, -9.81)


@dataclass(frozen=True)
class GraspJoint:
    """A sliding grasp in the model: the joint whose coordinate is ``rate * sigma``.

    Attributes
    ----------
    joint : str
        Name of the MJCF joint.
    rate : float
        ``d qpos / d sigma`` (1 for a slide, the signed curvature for a hinge).
    """

    joint: str
    rate: float


@dataclass(frozen=True)
class PhysicsModel:
    """The MJCF text and the names that read it.

    Attributes
    ----------
    xml : str
        The MJCF model.
    joints : dict of str to tuple of str
        The arm joints of ``"leader"`` and ``"follower"``, base to tip.
    grasps : dict of str to GraspJoint
        The sliding grasps by role (``"follower"``; ``"leader"`` when it slides).
    support_gap : str or None
        The joint of a support's normal motion (0 in contact, negative when apart).
    tools : dict of str to str
        The bodies of the arms' tool frames.
    points : dict of str to str
        The bodies whose origins are the grasp points (the leader's tool, the end of
        the follower's chain).
    welds : dict of str to int
        Index of each hand's weld among the model's equalities.
    mass, mass_centre
        The object's mass [kg] and mass centre [m, object frame].
    carried : float
        What the hands carry [kg]: the object and the bodies of its grasp chains
        (:data:`CHAIN_MASS` each).
    gravity : ndarray, shape (3,)
        [m/s^2], world.
    notes : list of str
        Simplifications taken for this task (reported in ``summary.json``).
    """

    xml: str
    joints: dict[str, tuple[str, ...]]
    grasps: dict[str, GraspJoint]
    support_gap: str | None
    tools: dict[str, str]
    points: dict[str, str]
    welds: dict[str, int]
    mass: float
    mass_centre: FloatArray
    gravity: FloatArray
    carried: float = 0.0
    notes: list[str] = field(default_factory=list)


def _f(values: Any) -> str:
    """Numbers as MJCF text, at full precision."""
    return " ".join(repr(float(v)) for v in np.ravel(values))


def _pose_attrs(T: Any) -> str:
    """``pos`` and ``quat`` (w x y z) attributes of a 4x4 pose or a ``pin.SE3``."""
    M = T if isinstance(T, pin.SE3) else pin.SE3(np.asarray(T, dtype=float))
    q = pin.Quaternion(M.rotation).coeffs()  # x y z w
    return f'pos="{_f(M.translation)}" quat="{_f([q[3], q[0], q[1], q[2]])}"'


def _axis(joint: Any) -> FloatArray:
    kind = joint.shortname()
    if kind == "JointModelRX":
        return np.array([1.0, 0.0, 0.0])
    if kind == "JointModelRY":
        return np.array([0.0, 1.0, 0.0])
    if kind == "JointModelRZ":
        return np.array([0.0, 0.0, 1.0])
    return np.asarray(joint.axis, dtype=float)


def _geom(shape: Capsule | Box | LinkGeom, T: FloatArray, name: str, extra: str = "") -> str:
    """Return a geom of ``shape`` given in a frame placed at ``T`` in the body."""
    if isinstance(shape, LinkGeom):
        return geom_xml(shape, T, name, extra)
    if isinstance(shape, Box):
        pose = T @ shape.pose
        return (f'<geom name="{name}" type="box" size="{_f(shape.half_size)}" '
                f'{_pose_attrs(pose)} {extra}/>')
    a = T[:3, :3] @ shape.a + T[:3, 3]
    b = T[:3, :3] @ shape.b + T[:3, 3]
    if np.linalg.norm(b - a) < 1e-6:
        return (f'<geom name="{name}" type="sphere" size="{shape.radius!r}" '
                f'pos="{_f(a)}" {extra}/>')
    return (f'<geom name="{name}" type="capsule" size="{shape.radius!r}" '
            f'fromto="{_f(np.r_[a, b])}" {extra}/>')


def _inertial(inertia: Any) -> str:
    J = np.asarray(inertia.inertia, dtype=float)
    full = [J[0, 0], J[1, 1], J[2, 2], J[0, 1], J[0, 2], J[1, 2]]
    return (f'<inertial pos="{_f(inertia.lever)}" mass="{inertia.mass!r}" '
            f'fullinertia="{_f(full)}"/>')


def _arm_xml(task: DualArmTask, role: str, arm: SerialArm, settings: PhysicsSettings,
             notes: list[str], assets: list[str]
             ) -> tuple[str, str, tuple[str, ...], list[str]]:
    """Return the arm's base geoms (world) and body tree; its joint names and its body names.

    The mesh assets its geoms refer to are appended to ``assets``.
    """
    model = arm.model
    by_joint: dict[int, list[tuple[Capsule | Box | LinkGeom, FloatArray, str]]] = {}
    for key, shapes in link_shapes(task, role, arm, settings, notes).items():
        frame = model.frames[arm.link_frame_ids[key]]
        for shape, name in shapes:
            by_joint.setdefault(int(frame.parentJoint), []).append(
                (shape, frame.placement.homogeneous, name))
            if isinstance(shape, LinkGeom) and shape.kind == "mesh":
                assets.append(mesh_xml(shape, name))
    moving = _contact_bits(settings, obstacle=False)
    base = "".join(_geom(s, T, name, moving) for s, T, name in by_joint.get(0, []))
    joints = tuple(f"{role}_{name}" for name in arm.joint_names)
    bodies = [f"{role}_link{j}" for j in range(1, model.njoints)]
    fallback = []
    xml, close = [], []
    for j in range(1, model.njoints):
        inert = model.inertias[j]
        has_inertia = inert.mass > 0 and np.all(np.linalg.eigvalsh(inert.inertia) > 0)
        geoms = by_joint.get(j, [])
        lines = [f'<body name="{bodies[j - 1]}" {_pose_attrs(model.jointPlacements[j])}>',
                 f'<joint name="{joints[j - 1]}" type="hinge" axis="{_f(_axis(model.joints[j]))}" '
                 f'armature="{settings.armature!r}" limited="false"/>']
        if has_inertia:
            lines.append(_inertial(inert))
        elif not geoms:
            lines.append('<inertial pos="0 0 0" mass="0.1" diaginertia="1e-4 1e-4 1e-4"/>')
            fallback.append(f"{bodies[j - 1]} (0.1 kg point)")
        else:
            fallback.append(bodies[j - 1])
        density = settings.link_density if not has_inertia else 0.0
        lines += [_geom(s, T, name, f'{moving} density="{density!r}"')
                  for s, T, name in geoms]
        if j == model.njoints - 1:
            tool = model.frames[arm.tool_frame_id].placement
            lines.append(f'<body name="{role}_tool" {_pose_attrs(tool)}>'
                         f'<inertial pos="0 0 0" mass="{CHAIN_MASS!r}" '
                         f'diaginertia="{_f([CHAIN_INERTIA] * 3)}"/>'
                         f'<site name="{role}_ft" pos="0 0 0"/></body>')
        xml += lines
        close.append("</body>")
    if fallback:
        notes.append(f"{role}: no inertia in the arm model for {', '.join(fallback)}: "
                     f"mass of its geometry at {settings.link_density:g} kg/m^3")
    return base, "\n".join(xml + close), joints, bodies


def _chain(name: str, surface: GraspSurface) -> tuple[str, GraspJoint]:
    """Return a frictionless sliding grasp: the path's joint, then the spin about the slide."""
    sj = surface.slide_joint()
    axis = "1 0 0" if sj.axis == "x" else "0 1 0"
    kind = "slide" if sj.kind == "prismatic" else "hinge"
    light = (f'<inertial pos="0 0 0" mass="{CHAIN_MASS!r}" '
             f'diaginertia="{_f([CHAIN_BODY_INERTIA] * 3)}"/>')
    xml = (f'<body name="{name}_path" {_pose_attrs(sj.placement)}>{light}'
           f'<joint name="{name}_slide" type="{kind}" axis="{axis}" limited="false"/>'
           f'<body name="{name}_point" {_pose_attrs(sj.child)}>{light}'
           f'<joint name="{name}_spin" type="hinge" axis="1 0 0" limited="false"/>'
           "</body></body>")
    return xml, GraspJoint(f"{name}_slide", float(sj.rate))


def _support_chain(name: str, surface: GraspSurface) -> tuple[str, GraspJoint, str]:
    """Return a support: free in every motion but into the object along the normal (one-sided)."""
    light = (f'<inertial pos="0 0 0" mass="{CHAIN_MASS!r}" '
             f'diaginertia="{_f([CHAIN_BODY_INERTIA] * 3)}"/>')
    sr = f'solreflimit="{_f(SOLREF)}"'
    xml = (f'<body name="{name}_path" {_pose_attrs(surface.pose(0.0))}>{light}'
           f'<joint name="{name}_slide" type="slide" axis="1 0 0" limited="false"/>'
           f'<joint name="{name}_side" type="slide" axis="0 1 0" limited="false"/>'
           f'<joint name="{name}_gap" type="slide" axis="0 0 1" limited="true" '
           f'range="-1 0" {sr}/>'
           f'<body name="{name}_point">{light}'
           f'<joint name="{name}_turn" type="ball" limited="false"/></body></body>')
    return xml, GraspJoint(f"{name}_slide", 1.0), f"{name}_gap"


def _object_shape(task: DualArmTask) -> tuple[Capsule | Box, bool]:
    """Return the object's shape (object frame), and whether the file gave it."""
    if task.scene is not None:
        for b in task.scene.bodies:
            if b.owner == "object":
                return b.shape, True
    s = task.surface
    ends = [np.asarray(s.point(s.sigma_min)), np.asarray(s.point(s.sigma_max))]
    hand = np.asarray(task.H1_inv[:3, 3] if task.leader_surface is None
                      else task.leader_surface.point(task.leader_surface.sigma_min))
    far = max(ends, key=lambda e: float(np.linalg.norm(e - hand)))
    return Capsule(hand, far, OBJECT_RADIUS), False


def _object_inertia(shape: Capsule | Box, mass: float) -> FloatArray:
    """Principal inertia of a uniform rod (capsule axis) or box of ``mass`` [kg m^2]."""
    if isinstance(shape, Box):
        a, b, c = shape.size
        d = np.array([b * b + c * c, a * a + c * c, a * a + b * b]) * mass / 12.0
        R = shape.pose[:3, :3]
        return np.asarray(R @ np.diag(d) @ R.T)
    axis = shape.b - shape.a
    L, r = float(np.linalg.norm(axis)), shape.radius
    if L < 1e-9:
        return np.eye(3) * 0.4 * mass * r * r
    u = axis / L
    perp = mass * (3 * r * r + L * L) / 12.0
    return np.asarray(perp * (np.eye(3) - np.outer(u, u)) + 0.5 * mass * r * r * np.outer(u, u))


def build_mjcf(task: DualArmTask, settings: PhysicsSettings) -> PhysicsModel:
    """Return the MJCF model of ``task`` (see the module docstring).

    Joint coordinates are not part of the text: the plant sets them
    (:class:`~dualarm_qp.physics.plant.MujocoPlant`). The free object body is placed at
    the origin; its pose is set with the joints.
    """
    notes: list[str] = []
    mass, centre, gravity = _object_mass(task, settings, notes)
    shape, given = _object_shape(task)
    if not given:
        notes.append(f"the object has no shape: a {OBJECT_RADIUS * 1e3:g} mm capsule from "
                     "the leader's hand to the far end of the follower's range")
    J = _object_inertia(shape, mass)
    full = [J[0, 0], J[1, 1], J[2, 2], J[0, 1], J[0, 2], J[1, 2]]
    joints, bodies, tree, base = {}, {}, [], []
    assets: list[str] = []
    for role, arm in (("leader", task.leader), ("follower", task.follower)):
        base_xml, body_xml, joints[role], bodies[role] = _arm_xml(task, role, arm, settings,
                                                                  notes, assets)
        base.append(base_xml)
        tree.append(body_xml)
    chains, grasps, support_gap = _grasp_chains(task)
    chain_mass = 2 * CHAIN_MASS * len(chains)
    notes.append(f"the grasp chains' bodies ride on the object: the hands carry "
                 f"{mass + chain_mass:g} kg ({chain_mass:g} kg of chain)")
    obstacles = []
    if task.scene is not None:
        obstacles = [_geom(b.shape, np.eye(4), f"obstacle_{b.name}",
                           _contact_bits(settings, obstacle=True))
                     for b in task.scene.obstacles]
    points = {"leader": "leader_tool" if task.leader_surface is None else "lgrasp_point",
              "follower": "fgrasp_point"}
    welds = _welds(task)
    excludes = [f'<exclude body1="object" body2="{b}"/>'
                for role in ("leader", "follower") for b in
                [*bodies[role][-WRIST_BODIES:], f"{role}_tool"]]
    object_geom = _geom(shape, np.eye(4), "object", _contact_bits(settings, obstacle=False))
    xml = "\n".join([
        '<mujoco model="dualarm_task">',
        '<compiler angle="radian" inertiafromgeom="auto" autolimits="false"/>',
        f'<option timestep="{SUBSTEP!r}" gravity="{_f(gravity)}" integrator="implicitfast" '
        'jacobian="dense" cone="elliptic"/>',
        '<default><geom friction="0.5 0.005 0.0001" solref="0.004 1" margin="0"/></default>',
        "<asset>", *assets, "</asset>",
        "<worldbody>", *base, *obstacles, *tree,
        '<body name="object" pos="0 0 0">',
        '<freejoint name="object_free"/>',
        f'<inertial pos="{_f(centre)}" mass="{mass!r}" fullinertia="{_f(full)}"/>',
        object_geom, *chains, "</body>",
        "</worldbody>",
        "<equality>", *welds, "</equality>",
        "<contact>", *excludes, "</contact>",
        "<actuator>", *_actuators(joints, settings), "</actuator>",
        "<sensor>", *(f'<force name="{role}_force" site="{role}_ft"/>'
                      f'<torque name="{role}_torque" site="{role}_ft"/>'
                      for role in ("leader", "follower")), "</sensor>",
        "</mujoco>", ""])
    return PhysicsModel(
        xml=xml, joints=joints, grasps=grasps, support_gap=support_gap,
        tools={"leader": "leader_tool", "follower": "follower_tool"}, points=points,
        welds={"leader": 0, "follower": 1}, mass=float(mass),
        mass_centre=np.asarray(centre, dtype=float), gravity=np.asarray(gravity, float),
        carried=float(mass + chain_mass), notes=notes)


def _object_mass(task: DualArmTask, settings: PhysicsSettings, notes: list[str]
                 ) -> tuple[float, FloatArray, FloatArray]:
    """Return the object's mass [kg], mass centre [m, object] and gravity [m/s^2].

    The task's load; without one, the settings' mass at the middle of the object's shape
    (noted in ``notes``).
    """
    load = task.load
    if load is not None:
        return load.mass, load.mass_centre, load.gravity
    shape0, _ = _object_shape(task)
    mid = (0.5 * (shape0.a + shape0.b) if isinstance(shape0, Capsule)
           else shape0.centre)
    mass, centre, gravity = settings.object_mass, np.asarray(mid), np.array(GRAVITY)
    notes.append(f"the object states no mass: {mass:g} kg at the middle of its shape")
    return mass, centre, gravity


def _grasp_chains(task: DualArmTask) -> tuple[list[str], dict[str, GraspJoint], str | None]:
    """Return the grasp chains' bodies, their joints, and a support's gap joint (or None)."""
    grasps: dict[str, GraspJoint] = {}
    chains = []
    support_gap = None
    if task.contact is not None:
        xml, grasps["follower"], support_gap = _support_chain("fgrasp", task.surface)
        chains.append(xml)
    else:
        xml, grasps["follower"] = _chain("fgrasp", task.surface)
        chains.append(xml)
    if task.leader_surface is not None:
        xml, grasps["leader"] = _chain("lgrasp", task.leader_surface)
        chains.append(xml)
    return chains, grasps, support_gap


def _welds(task: DualArmTask) -> list[str]:
    """Return the welds of the hands: the leader's to the object (or its grasp point)."""
    solref = f'solref="{_f(SOLREF)}"'
    return ['<weld name="weld_leader" body1="leader_tool" body2="object" '
            f'relpose="{_f(_pose_vec(task.H1))}" {solref}/>'
            if task.leader_surface is None else
            '<weld name="weld_leader" body1="leader_tool" body2="lgrasp_point" '
            f'relpose="0 0 0 1 0 0 0" {solref}/>',
            '<weld name="weld_follower" body1="follower_tool" body2="fgrasp_point" '
            f'relpose="0 0 0 1 0 0 0" {solref}/>']


def _pose_vec(T: FloatArray) -> FloatArray:
    M = pin.SE3(np.asarray(T, dtype=float))
    q = pin.Quaternion(M.rotation).coeffs()
    return np.r_[M.translation, q[3], q[0], q[1], q[2]]


def _contact_bits(settings: PhysicsSettings, *, obstacle: bool) -> str:
    """Return the ``contype``/``conaffinity`` of a geom under ``settings.contacts``.

    MuJoCo lets two geoms touch when ``contype`` of one meets ``conaffinity`` of the
    other: under ``obstacles`` the moving geoms have (1, 0) and the obstacles (0, 1).
    """
    if settings.contacts == "none":
        return 'contype="0" conaffinity="0"'
    if settings.contacts == "all":
        return 'contype="1" conaffinity="1"'
    return 'contype="0" conaffinity="1"' if obstacle else 'contype="1" conaffinity="0"'


def _actuators(joints: dict[str, tuple[str, ...]], settings: PhysicsSettings) -> list[str]:
    """Each arm joint's servo: a position actuator (kp) and a velocity actuator (kv).

    The gains written are the file's ``kp`` and ``kv`` (1 where it states none): the
    plant sets each joint's from the arm's inertia once the model is compiled
    (:mod:`~dualarm_qp.physics.gains`).
    """
    kp = 1.0 if settings.kp is None else settings.kp
    kv = 1.0 if settings.kv is None else settings.kv
    out = []
    for name in (*joints["leader"], *joints["follower"]):
        if settings.servo == "position":
            out.append(f'<position name="{name}_p" joint="{name}" kp="{kp!r}"/>')
        out.append(f'<velocity name="{name}_v" joint="{name}" kv="{kv!r}"/>')
    return out


__all__ = ["GraspJoint", "PhysicsModel", "build_mjcf"]
