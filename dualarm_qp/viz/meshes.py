"""The visual geometry of URDF arms for the 3D view: which shapes, on which node, where.

An arm built from a URDF (:func:`~dualarm_qp.kinematics.urdf_arm`,
:func:`~dualarm_qp.kinematics.example_robot_arm`) records the file and the chain in
:attr:`~dualarm_qp.kinematics.SerialArm.source`. From it this module reads the
``<visual>`` elements of the URDF's links and hangs each on a node of the view (node 0
the arm's base, node ``k`` the frame of the arm's joint ``k``, see :mod:`.scene`):

- a link moved by a joint of the chain follows the nearest such joint above it, matched
  by joint name (links after the tip, such as a hand and its fingers, follow the last
  joint, with every joint outside the chain at zero, as the arm's model has it);
- a link on the way from the chain's root to its first joint is fixed to the base;
- every other link (the other arm of a dual-arm robot, a head, a pedestal) is left out.

Each visual keeps its pose in its node, ``T_node_visual`` [m], so the page moves it with
the node alone. Meshes are read in Python (:mod:`.mesh_files`) into triangle buffers
that the page draws without any loader. A mesh that cannot be found or read is reported,
never raised: the view then draws the arm's link capsules as well.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from ..kinematics.arm import SerialArm
from .mesh_files import MeshError, MeshLibrary, resolve_mesh

FloatArray = NDArray[np.float64]
IndexArray = NDArray[np.uint32]

#: Kinds of :attr:`SerialArm.source` that name a URDF: ``<kind>:<where> <root>-><tip>``.
_SOURCE_KINDS = ("urdf", "example_robot")


@dataclass(frozen=True)
class Visual:
    """One ``<visual>`` of a URDF link.

    Attributes
    ----------
    link : str
        The link's name.
    origin : ndarray, shape (4, 4)
        ``T_link_visual``, the visual's ``<origin>`` [m].
    kind : str
        ``"mesh"``, ``"box"``, ``"cylinder"`` or ``"sphere"``.
    filename : str
        The mesh's URI as written (``package://...``, ``file://...`` or a path).
    scale : tuple of float
        The mesh's scale along its x, y, z.
    size : tuple of float
        Box edges (x, y, z) [m]; cylinder (radius, length along z) [m]; sphere (radius,) [m].
    """

    link: str
    origin: FloatArray
    kind: str
    filename: str = ""
    scale: tuple[float, float, float] = (1.0, 1.0, 1.0)
    size: tuple[float, ...] = ()


@dataclass(frozen=True)
class PlacedVisual:
    """A visual hung on a node of the view: ``T_node_visual`` [m] stays constant."""

    node: int
    pose: FloatArray
    visual: Visual


@dataclass
class ArmVisuals:
    """What an arm's URDF gives the view.

    Attributes
    ----------
    placed : list of PlacedVisual
        Every visual of the arm's links, in URDF order.
    parts : list of dict
        Those that could be drawn, as scene parts (``node``, ``shape``, 4x4 ``pose``
        [m], and ``mesh`` with ``scale`` or the primitive's sizes).
    missing : list of str
        Those that could not, each with the reason.
    """

    placed: list[PlacedVisual]
    parts: list[dict[str, Any]] = field(default_factory=list)
    missing: list[str] = field(default_factory=list)


# ------------------------------------------------------------------ URDF reading
def _floats(text: str | None, count: int, default: float) -> tuple[float, ...]:
    if not text:
        return (default,) * count
    values = tuple(float(v) for v in text.split())
    if len(values) != count:
        raise ValueError(f"expected {count} numbers, got {text!r}")
    return values


def _origin(element: ET.Element | None) -> FloatArray:
    T = np.eye(4)
    if element is not None:
        roll, pitch, yaw = _floats(element.get("rpy"), 3, 0.0)
        T[:3, :3] = pin.rpy.rpyToMatrix(roll, pitch, yaw)
        T[:3, 3] = _floats(element.get("xyz"), 3, 0.0)
    return T


def _visual(link: str, element: ET.Element) -> Visual | None:
    """Read one ``<visual>``; None when it holds no geometry we draw."""
    geometry = element.find("geometry")
    if geometry is None or len(geometry) == 0:
        return None
    shape = geometry[0]
    origin = _origin(element.find("origin"))
    if shape.tag == "mesh":
        sx, sy, sz = _floats(shape.get("scale"), 3, 1.0)
        return Visual(link, origin, "mesh", filename=shape.get("filename", ""),
                      scale=(sx, sy, sz))
    if shape.tag == "box":
        return Visual(link, origin, "box", size=_floats(shape.get("size"), 3, 0.0))
    if shape.tag == "cylinder":
        size = (float(shape.get("radius", 0.0)), float(shape.get("length", 0.0)))
        return Visual(link, origin, "cylinder", size=size)
    if shape.tag == "sphere":
        return Visual(link, origin, "sphere", size=(float(shape.get("radius", 0.0)),))
    return None


def read_urdf_visuals(path: str | Path) -> dict[str, tuple[Visual, ...]]:
    """Return the visuals of every link of a URDF file, by link name, in file order.

    Parameters
    ----------
    path : str or Path
        The URDF file.

    Raises
    ------
    MeshError
        The file cannot be read or parsed.
    """
    try:
        mtime = Path(path).stat().st_mtime
    except OSError as err:
        raise MeshError(f"cannot read the URDF {path}: {err.strerror or err}") from None
    return _read_urdf_visuals(str(path), mtime)


@lru_cache(maxsize=16)
def _read_urdf_visuals(path: str, mtime: float) -> dict[str, tuple[Visual, ...]]:
    try:
        robot = ET.parse(path).getroot()
    except (OSError, ET.ParseError) as err:
        raise MeshError(f"cannot read the URDF {path}: {err}") from None
    visuals: dict[str, tuple[Visual, ...]] = {}
    for link in robot.iter("link"):
        name = link.get("name", "")
        try:
            found = [_visual(name, v) for v in link.findall("visual")]
        except ValueError as err:
            raise MeshError(f"{path}: link {name!r}: bad visual ({err})") from None
        visuals[name] = tuple(v for v in found if v is not None)
    return visuals


def urdf_of(arm: SerialArm) -> tuple[Path, str, str] | None:
    """Return the URDF file and the chain's root and tip an arm was built from, or None.

    Reads :attr:`~dualarm_qp.kinematics.SerialArm.source` (``urdf:<file> <root>-><tip>``
    or ``example_robot:<robot> <root>-><tip>``); None for a DH arm or a model given
    directly.
    """
    kind, _, rest = arm.source.partition(":")
    if kind not in _SOURCE_KINDS or " " not in rest:
        return None
    where, chain = rest.rsplit(" ", 1)
    root, arrow, tip = chain.partition("->")
    if not arrow:
        return None
    if kind == "urdf":
        return Path(where), root, tip
    from ..kinematics.robots import RobotModelError, example_robot_urdf

    try:
        return example_robot_urdf(where), root, tip
    except RobotModelError:
        return None


@lru_cache(maxsize=16)
def _full_model(path: str, mtime: float) -> Any:
    return pin.buildModelFromUrdf(path)


def _frame(model: Any, name: str, kind: Any = None) -> int | None:
    ids = [i for i, f in enumerate(model.frames)
           if f.name == name and (kind is None or f.type == kind)]
    if not ids:
        return None
    body = [i for i in ids if model.frames[i].type == pin.FrameType.BODY]
    return (body or ids)[0]


def place_visuals(arm: SerialArm) -> list[PlacedVisual] | None:
    """Hang the visuals of an arm's URDF links on the arm's nodes (module docstring).

    Returns
    -------
    list of PlacedVisual or None
        ``T_node_visual`` [m] of each visual, node 0 the base and node ``k`` the frame of
        joint ``k``; None when the arm was not built from a URDF.

    Raises
    ------
    MeshError
        The URDF cannot be read again, or its joints no longer match the arm's.
    """
    found = urdf_of(arm)
    if found is None:
        return None
    path, root, _tip = found
    visuals = read_urdf_visuals(path)
    try:
        full = _full_model(str(path), path.stat().st_mtime)
    except (OSError, RuntimeError, ValueError) as err:
        raise MeshError(f"cannot read the URDF {path}: {err}") from None
    chain: dict[int, int] = {}
    for k, name in enumerate(arm.joint_names):
        if not full.existJointName(name):
            raise MeshError(f"{path}: the arm's joint {name!r} is not in the URDF")
        chain[int(full.getJointId(name))] = k + 1
    root_id = _frame(full, root)
    first = _frame(full, arm.joint_names[0], pin.FrameType.JOINT)
    if root_id is None or first is None:
        raise MeshError(f"{path}: frame {root!r} or joint {arm.joint_names[0]!r} not found")
    fixed_to_base = set()  # links from the root down to the chain's first joint
    i = first
    while i != 0 and i != root_id:
        i = int(full.frames[i].parentFrame)
        if full.frames[i].type == pin.FrameType.BODY:
            fixed_to_base.add(full.frames[i].name)
    data = full.createData()
    pin.forwardKinematics(full, data, pin.neutral(full))
    pin.updateFramePlacements(full, data)
    placed = []
    for link, items in visuals.items():
        f = _frame(full, link, pin.FrameType.BODY)
        if f is None or not items:
            continue
        j = int(full.frames[f].parentJoint)
        while j != 0 and j not in chain:
            j = int(full.parents[j])
        if j in chain:
            node, T_world_node = chain[j], data.oMi[j]
        elif link in fixed_to_base:
            node, T_world_node = 0, data.oMf[root_id]
        else:
            continue
        T_node_link = (T_world_node.inverse() * data.oMf[f]).homogeneous
        placed += [PlacedVisual(node, T_node_link @ v.origin, v) for v in items]
    return placed


def arm_visuals(arm: SerialArm, library: MeshLibrary) -> ArmVisuals | None:
    """Read the visual geometry of an arm built from a URDF; None for any other arm.

    Meshes go into ``library``; what cannot be read is listed in ``missing``, never
    raised.

    Parameters
    ----------
    arm : SerialArm
        The arm.
    library : MeshLibrary
        Where the meshes are stored (shared by both arms of a scene).
    """
    found = urdf_of(arm)
    if found is None:
        return None
    try:
        placed = place_visuals(arm)
    except MeshError as err:
        return ArmVisuals(placed=[], missing=[str(err)])
    if placed is None:
        return None
    result = ArmVisuals(placed=placed)
    for p in placed:
        v = p.visual
        part: dict[str, Any] = {"node": p.node, "pose": p.pose, "link": v.link}
        if v.kind == "mesh":
            try:
                part.update(shape="mesh", scale=list(v.scale),
                            mesh=library.add(resolve_mesh(v.filename, found[0])))
            except MeshError as err:
                result.missing.append(f"{v.link}: {err}")
                continue
        elif v.kind == "box":
            part.update(shape="box", size=list(v.size))
        elif v.kind == "sphere":
            part.update(shape="sphere", radius=v.size[0])
        else:  # a URDF cylinder lies along z, a three.js one along y: turn y onto z
            turn = np.eye(4)
            turn[1:3, 1:3] = [[0.0, -1.0], [1.0, 0.0]]
            part.update(shape="cylinder", radius=v.size[0], length=v.size[1],
                        pose=p.pose @ turn)
        result.parts.append(part)
    return result
