"""An independent forward-kinematics oracle for one chain of a URDF file.

Written from the URDF specification alone: the file is read as XML, and each joint's
``origin`` (``xyz``; ``rpy`` as R = Rz(yaw) Ry(pitch) Rx(roll)) and ``axis`` (default
x) are chained from the ``root`` link to the ``tip`` link with plain numpy 4x4 products
(a revolute or continuous joint turns by Rodrigues' formula about its axis; a continuous
joint has no range, whatever its ``limit`` tag says, as the URDF specification has it).
It shares no code with ``dualarm_qp.kinematics`` nor with Pinocchio. Lengths in m, angles in rad.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np


def _floats(text: str | None, default: tuple[float, float, float]) -> np.ndarray:
    return np.array(default if text is None else [float(v) for v in text.split()])


def rpy_matrix(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """URDF's fixed-axis roll, pitch, yaw: ``Rz(yaw) Ry(pitch) Rx(roll)``."""
    cr, sr, cp, sp, cy, sy = (np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch),
                              np.cos(yaw), np.sin(yaw))
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return rz @ ry @ rx


def config_pose(spec: dict) -> np.ndarray:
    """A pose of an experiment file in mm and degrees (``position``, ``rotation`` or ``rpy``)."""
    T = np.eye(4)
    T[:3, 3] = np.array(spec.get("position", [0, 0, 0]), dtype=float) / 1000.0
    if "rotation" in spec:
        T[:3, :3] = np.array(spec["rotation"], dtype=float)
    elif "rpy" in spec:
        T[:3, :3] = rpy_matrix(*np.deg2rad(spec["rpy"]))
    return T


def axis_rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rotation by ``angle`` about the unit vector ``axis`` (Rodrigues)."""
    k = axis / np.linalg.norm(axis)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * (K @ K)


def homogeneous(R: np.ndarray, p: np.ndarray) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = p
    return T


#: The joints that turn about their axis.
TURNING = ("revolute", "continuous")


@dataclass(frozen=True)
class Joint:
    """One joint of the chain, as written in the URDF."""

    name: str
    kind: str                  # "revolute", "continuous", "fixed", ...
    origin: np.ndarray         # 4x4, parent link -> joint frame at zero angle
    axis: np.ndarray           # (3,), in the joint frame
    lower: float
    upper: float
    velocity: float


class UrdfChain:
    """The joints from link ``root`` down to link ``tip`` of a URDF file.

    Raises ``ValueError`` when ``tip`` is not below ``root``, or a joint on the way
    moves but is not revolute.
    """

    def __init__(self, path: str | Path, root: str, tip: str) -> None:
        xml = ET.parse(path).getroot()
        by_child = {j.find("child").get("link"): j  # type: ignore[union-attr]
                    for j in xml.findall("joint")}
        chain = []
        link = tip
        while link != root:
            if link not in by_child:
                raise ValueError(f"{tip!r} is not below {root!r} in {path}")
            element = by_child[link]
            chain.append(self._joint(element))
            link = str(element.find("parent").get("link"))  # type: ignore[union-attr]
        self.joints = chain[::-1]
        for j in self.joints:
            if j.kind not in (*TURNING, "fixed"):
                raise ValueError(f"joint {j.name!r} is {j.kind}")
        self.moving = [j for j in self.joints if j.kind in TURNING]

    @staticmethod
    def _joint(element: ET.Element) -> Joint:
        origin = element.find("origin")
        xyz = _floats(None if origin is None else origin.get("xyz"), (0.0, 0.0, 0.0))
        rpy = _floats(None if origin is None else origin.get("rpy"), (0.0, 0.0, 0.0))
        axis_tag = element.find("axis")
        axis = _floats(None if axis_tag is None else axis_tag.get("xyz"), (1.0, 0.0, 0.0))
        limit = element.find("limit")

        kind = str(element.get("type"))

        def bound(key: str, default: float) -> float:
            value = None if limit is None else limit.get(key)
            if kind == "continuous" and key in ("lower", "upper"):
                return default  # no range
            return default if value is None else float(value)

        return Joint(str(element.get("name")), kind,
                     homogeneous(rpy_matrix(*rpy), xyz), axis,
                     bound("lower", -np.inf), bound("upper", np.inf),
                     bound("velocity", np.inf))

    @property
    def names(self) -> list[str]:
        """Names of the moving joints, root to tip (the CSV's column order)."""
        return [j.name for j in self.moving]

    def frames(self, q: np.ndarray, base: np.ndarray) -> list[np.ndarray]:
        """World poses of every joint frame (moving and fixed) and of the tip, in order."""
        q = np.asarray(q, dtype=float)
        if q.shape != (len(self.moving),):
            raise ValueError(f"expected {len(self.moving)} joint values, got {q.shape}")
        T = np.array(base, dtype=float)
        out = []
        values = iter(q)
        for j in self.joints:
            T = T @ j.origin
            if j.kind in TURNING:
                T = T @ homogeneous(axis_rotation(j.axis, next(values)), np.zeros(3))
            out.append(T)
        return out

    def fk(self, q: np.ndarray, base: np.ndarray, tool: np.ndarray) -> np.ndarray:
        """``T_world_tool = base @ (origin_i @ Rot(axis_i, q_i))... @ tool`` (4x4)."""
        return self.frames(q, base)[-1] @ np.asarray(tool, dtype=float)


def rotation_angle(R: np.ndarray) -> float:
    """Angle [rad] of a rotation matrix (0 for the identity)."""
    c = (np.trace(R) - 1.0) / 2.0
    return float(np.arccos(np.clip(c, -1.0, 1.0)))


def plane_bar_pose(sigma: float) -> np.ndarray:
    """The config's ``plane_bar`` grasp frame (Eq. 3, Fig. 4) in object coordinates.

    The path is the object z axis on the face x = 0: position ``sigma * z``; frame
    columns ``[s*, n*, a*]`` with ``s* = z``, ``a* = x`` and ``n* = a* x s* = -y``.
    """
    R = np.array([[0.0, 0.0, 1.0], [0.0, -1.0, 0.0], [1.0, 0.0, 0.0]])
    return homogeneous(R, np.array([0.0, 0.0, sigma]))
