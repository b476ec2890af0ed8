"""The collision geometry of a URDF arm's links, as MuJoCo geoms: hulls and primitives.

MuJoCo collides a mesh through its convex hull, so each collision mesh of the URDF (a
DAE, STL or OBJ file, read by Pinocchio through coal, with the file's ``scale``
applied) becomes the convex hull of its vertices, given inline in the MJCF as
``<mesh vertex="x y z ...">`` (only the hull's vertices, so that the text stays
small; no file is written). A collision primitive stays a primitive: a URDF ``box``,
``sphere`` or ``cylinder`` (and a coal capsule or ellipsoid) is MuJoCo's own; a cone is
given as the hull of its rim polygon and apex.

Each geometry is placed in the frame of the arm's joint that moves it, as the capsules
of :mod:`dualarm_qp.geometry.links` are: key ``i`` (1..n) holds the geometry of every
link joint ``i`` moves (locked joints below it, a gripper's, included) in the frame of
joint ``i``; key 0 the geometry of the root link and the links fixed to it, in the
arm's base frame. Geometry of the robot that is not on the chain (another arm, a head)
is left out.

Which geometry an arm gets in the MJCF is :func:`link_shapes`'s choice: a URDF arm's
collision geometry under ``geometry: meshes`` (the default), else the project's
capsules (:mod:`dualarm_qp.geometry.links`, or the collision scene's when the task has
one); a DH arm has no meshes, so it always gets capsules.

Nothing here imports MuJoCo: the geometry is text (:func:`geom_xml`, :func:`mesh_xml`).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import coal  # type: ignore[import-untyped]
import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from ..errors import InvalidInputError
from ..geometry.fit import geometry_balls
from ..geometry.links import arm_capsules, arm_urdf_chain, chain_collision_objects
from ..geometry.shapes import Box, Capsule
from ..kinematics.arm import SerialArm
from ..task.scene import DualArmTask
from .settings import PhysicsSettings

FloatArray = NDArray[np.float64]

#: Radius [m] of a DH arm's capsules when neither the scene nor a preset gives them.
DEFAULT_RADIUS = 0.05


@dataclass(frozen=True)
class LinkGeom:
    """One collision geometry of a link, as a MuJoCo geom.

    Attributes
    ----------
    name : str
        The URDF collision object's name (Pinocchio's geometry object name).
    kind : {"mesh", "box", "sphere", "cylinder", "capsule", "ellipsoid"}
        MuJoCo geom type.
    pose : ndarray, shape (4, 4)
        Pose of the geometry in its link frame (the frame of the joint that moves it,
        or the arm's base frame) [m].
    size : ndarray
        MuJoCo's ``size`` of a primitive [m]: half sizes (box), radius (sphere),
        radius and half length along z (cylinder, capsule), radii (ellipsoid); empty
        for a mesh.
    vertices : ndarray, shape (m, 3) or None
        A mesh's convex hull vertices in the geometry's frame [m]; None for a primitive.
    """

    name: str
    kind: str
    pose: FloatArray
    size: FloatArray
    vertices: FloatArray | None = None


def hull_vertices(points: Any) -> FloatArray:
    """Return the vertices of the convex hull of ``points`` (m, 3) [m], in input order.

    Raises
    ------
    InvalidInputError
        Fewer than four points, or points that span no volume (a flat mesh): MuJoCo
        cannot collide such a mesh.
    """
    from scipy.spatial import ConvexHull, QhullError  # SciPy is slow to import

    v = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    try:
        hull = ConvexHull(v)
    except (QhullError, ValueError) as err:
        raise InvalidInputError(f"a collision mesh of {v.shape[0]} vertices spans no "
                                f"volume, so it has no convex hull ({err.__class__.__name__})"
                                ) from None
    out: FloatArray = v[np.sort(hull.vertices)]
    return out


def link_geom(name: str, geometry: Any, pose: Any) -> LinkGeom:
    """Return the MuJoCo geom of one coal collision geometry placed at ``pose`` [m].

    Raises
    ------
    InvalidInputError
        A geometry without a bounded convex cover (see
        :func:`~dualarm_qp.geometry.fit.geometry_balls`) or a flat mesh.
    """
    T = np.asarray(pose, dtype=np.float64)
    g = geometry
    swept = float(g.getSweptSphereRadius()) if isinstance(g, coal.ShapeBase) else 0.0
    if swept == 0.0:
        if isinstance(g, coal.Box):
            return LinkGeom(name, "box", T, np.array(g.halfSide, dtype=np.float64))
        if isinstance(g, coal.Sphere):
            return LinkGeom(name, "sphere", T, np.array([float(g.radius)]))
        if isinstance(g, coal.Cylinder | coal.Capsule):
            kind = "cylinder" if isinstance(g, coal.Cylinder) else "capsule"
            return LinkGeom(name, kind, T, np.array([float(g.radius), float(g.halfLength)]))
        if isinstance(g, coal.Ellipsoid):
            return LinkGeom(name, "ellipsoid", T, np.array(g.radii, dtype=np.float64))
    points, radii = geometry_balls(g)  # a mesh's vertices; a cone's rim and apex
    if np.any(radii > 0.0):
        raise InvalidInputError(f"collision geometry {name!r}: a {type(g).__name__} "
                                "with a swept-sphere radius has no MuJoCo geom")
    try:
        hull = hull_vertices(points)
    except InvalidInputError as err:
        raise InvalidInputError(f"collision geometry {name!r}: {err}; set physics.geometry: "
                                "capsules to use the capsules instead") from None
    return LinkGeom(name, "mesh", T, np.zeros(0), hull)


def urdf_link_geoms(file: str | Path, root: str, tip: str, *,
                    package_dirs: Any = None) -> dict[int, tuple[LinkGeom, ...]]:
    """Return the collision geometry of the arm ``urdf_arm(file, root, tip)`` per link frame.

    Parameters
    ----------
    file : str or Path
        The URDF file.
    root, tip : str
        The arm's base and flange frames, as for :func:`~dualarm_qp.kinematics.urdf_arm`.
    package_dirs : sequence of str or Path, optional
        Folders in which ``package://`` mesh paths are looked up; default every folder
        above the URDF file.

    Returns
    -------
    dict of int to tuple of LinkGeom
        Keyed like :meth:`SerialArm.link_frames
        <dualarm_qp.kinematics.SerialArm.link_frames>` (see the module docstring).

    Raises
    ------
    RobotModelError
        Unreadable URDF or meshes, or a chain ``urdf_arm`` rejects
        (:func:`~dualarm_qp.geometry.links.chain_collision_objects`).
    InvalidInputError
        A geometry MuJoCo cannot collide (see :func:`link_geom`).

    Notes
    -----
    The result is kept for the life of the process, keyed by the file's path, size and
    modification time, the chain and the package folders.
    """
    path = Path(file).resolve()
    dirs = None if package_dirs is None else tuple(str(p) for p in package_dirs)
    try:
        st = path.stat()
    except OSError:
        return _read(path, root, tip, dirs)
    key = (str(path), st.st_size, st.st_mtime_ns, root, tip, dirs)
    if key not in _READ:
        if len(_READ) >= _READ_MAX:
            _READ.pop(next(iter(_READ)))
        _READ[key] = _read(path, root, tip, dirs)
    return dict(_READ[key])


#: Geometry already read in this process (:func:`urdf_link_geoms`), at most ``_READ_MAX``.
_READ: dict[tuple[Any, ...], dict[int, tuple[LinkGeom, ...]]] = {}
_READ_MAX = 32


def _read(path: Path, root: str, tip: str, dirs: tuple[str, ...] | None
          ) -> dict[int, tuple[LinkGeom, ...]]:
    """Read and convert the geometry of :func:`urdf_link_geoms` (uncached)."""
    out: dict[int, list[LinkGeom]] = {}
    for key, obj, pose in chain_collision_objects(path, root, tip, package_dirs=dirs):
        out.setdefault(key, []).append(link_geom(obj.name, obj.geometry, pose.homogeneous))
    return {key: tuple(geoms) for key, geoms in sorted(out.items())}


def arm_link_geoms(arm: SerialArm) -> dict[int, tuple[LinkGeom, ...]]:
    """Return :func:`urdf_link_geoms` of the file and chain recorded in ``arm.source``.

    Raises
    ------
    InvalidInputError
        A DH arm (it has no collision geometry of its own), or an arm built from a
        bare Pinocchio model (no file to read).
    """
    recorded = arm_urdf_chain(arm)
    if recorded is None:
        raise InvalidInputError(f"{arm.name}: no robot file recorded for this arm "
                                f"(source {arm.source!r}): no collision meshes")
    return urdf_link_geoms(*recorded)


def _capsules(task: DualArmTask, role: str, arm: SerialArm, notes: list[str]
              ) -> dict[int, Capsule | Box]:
    """Each link's shape, keyed like ``arm.link_frames``: the scene's, else the arm's own."""
    if task.scene is not None:
        return {b.link: b.shape for b in task.scene.bodies if b.owner == role}
    try:
        return dict(arm_capsules(arm))
    except InvalidInputError:
        if arm.dh is None:
            raise
        notes.append(f"{role}: no capsule radii for this DH arm: every link is a "
                     f"{DEFAULT_RADIUS * 1e3:g} mm capsule")
        return dict(arm_capsules(arm, radii=np.full(arm.n, DEFAULT_RADIUS)))


def link_shapes(task: DualArmTask, role: str, arm: SerialArm, settings: PhysicsSettings,
                notes: list[str]) -> dict[int, list[tuple[Capsule | Box | LinkGeom, str]]]:
    """Each link's shapes and geom names in the MJCF, keyed like ``arm.link_frames``.

    A URDF arm under ``settings.geometry == "meshes"``: its collision geometry
    (:func:`arm_link_geoms`); otherwise its capsules (:func:`_capsules`). A
    simplification taken is appended to ``notes``.
    """
    if settings.geometry == "meshes" and arm.dh is None:
        geoms = arm_link_geoms(arm)
        hulls = sum(g.kind == "mesh" for gs in geoms.values() for g in gs)
        count = sum(len(gs) for gs in geoms.values())
        notes.append(f"{role}: the URDF's collision geometry: {hulls} meshes as their "
                     f"convex hulls, {count - hulls} primitives")
        return {k: [(g, f"{role}_{g.name}") for g in gs] for k, gs in geoms.items()}
    if settings.geometry == "meshes":
        notes.append(f"{role}: a DH arm has no collision meshes: capsules")
    return {k: [(s, f"{role}_{'base_' if k == 0 else 'link'}{k}")]
            for k, s in _capsules(task, role, arm, notes).items()}


def _f(values: Any) -> str:
    """Numbers as MJCF text, at full precision."""
    return " ".join(repr(float(v)) for v in np.ravel(values))


def geom_xml(geom: LinkGeom, T: Any, name: str, extra: str = "") -> str:
    """Return the ``<geom>`` of ``geom`` in a body whose link frame is at ``T`` (4x4).

    A mesh geom refers to the asset of :func:`mesh_xml` called ``name``.
    """
    M = pin.SE3(np.asarray(T, dtype=np.float64) @ geom.pose)
    q = pin.Quaternion(M.rotation).coeffs()  # x y z w
    pose = f'pos="{_f(M.translation)}" quat="{_f([q[3], q[0], q[1], q[2]])}"'
    shape = (f'type="mesh" mesh="{name}"' if geom.kind == "mesh"
             else f'type="{geom.kind}" size="{_f(geom.size)}"')
    return f'<geom name="{name}" {shape} {pose} {extra}/>'


def mesh_xml(geom: LinkGeom, name: str) -> str:
    """Return the ``<mesh>`` asset of a mesh geom: its hull vertices inline, no file."""
    if geom.vertices is None:
        raise InvalidInputError(f"{geom.name}: a {geom.kind} is a primitive, not a mesh")
    return f'<mesh name="{name}" vertex="{_f(geom.vertices)}"/>'


__all__ = ["DEFAULT_RADIUS", "LinkGeom", "arm_link_geoms", "geom_xml", "hull_vertices",
           "link_geom", "link_shapes", "mesh_xml", "urdf_link_geoms"]
