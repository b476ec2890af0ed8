"""An independent quasi-static joint torque oracle for one chain of a URDF file.

Written from the URDF specification and rigid-body statics alone; it shares no code with
``dualarm_qp`` nor with Pinocchio. Every link of the robot's tree gets its world pose by
chaining the joints' ``origin`` from the root (the chain's revolute joints at the given
angles, every other joint at zero, as the arm locks them), and its mass at its
``inertial`` origin. A revolute joint ``j`` of the chain, with world axis ``a_j`` through
``o_j``, holds every link below it and the hand's load:

    tau_j = sum_i m_i (a_j x (c_i - o_j)) . (-g)  +  a_j . (m + (p - o_j) x f),

``[f; m]`` the wrench the hand applies to the object (world frame, moment about the
tool point ``p``): the object pushes back with ``-[f; m]``.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
from urdf_oracle import UrdfChain, axis_rotation, homogeneous, rpy_matrix


def _floats(text: str | None, n: int = 3) -> np.ndarray:
    return np.zeros(n) if text is None else np.array([float(v) for v in text.split()])


class UrdfStatics:
    """Gravity and load torques of the chain ``root`` -> ``tip`` of a URDF."""

    def __init__(self, path: str | Path, root: str, tip: str) -> None:
        xml = ET.parse(path).getroot()
        self.chain = UrdfChain(path, root, tip)
        self.moving = self.chain.names
        self.children: dict[str, list[ET.Element]] = {}
        for j in xml.findall("joint"):
            parent = j.find("parent").get("link")  # type: ignore[union-attr]
            self.children.setdefault(str(parent), []).append(j)
        self.mass: dict[str, tuple[float, np.ndarray]] = {}
        for link in xml.findall("link"):
            inertial = link.find("inertial")
            if inertial is None:
                continue
            m = float(inertial.find("mass").get("value"))  # type: ignore[union-attr]
            origin = inertial.find("origin")
            xyz = _floats(None if origin is None else origin.get("xyz"))
            self.mass[str(link.get("name"))] = (m, xyz)
        self.root = root

    def _walk(self, q: dict[str, float], base: np.ndarray
              ) -> tuple[dict[str, np.ndarray], dict[str, tuple[np.ndarray, np.ndarray]],
                         dict[str, set[str]]]:
        """World poses of the links below the root, the chain joints' axes, their links."""
        poses = {self.root: np.asarray(base, dtype=float)}
        axes: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        below: dict[str, set[str]] = {name: set() for name in self.moving}
        stack = [(self.root, frozenset())]
        while stack:
            link, movers = stack.pop()
            for j in self.children.get(link, []):
                origin = j.find("origin")
                xyz = _floats(None if origin is None else origin.get("xyz"))
                rpy = _floats(None if origin is None else origin.get("rpy"))
                T = poses[link] @ homogeneous(rpy_matrix(*rpy), xyz)
                name = str(j.get("name"))
                child = str(j.find("child").get("link"))  # type: ignore[union-attr]
                now = set(movers)
                if j.get("type") in ("revolute", "continuous"):
                    axis_tag = j.find("axis")
                    axis = (np.array([1.0, 0.0, 0.0]) if axis_tag is None
                            else _floats(axis_tag.get("xyz")))
                    angle = q.get(name, 0.0)
                    if name in below:
                        axes[name] = (T[:3, :3] @ axis / np.linalg.norm(axis), T[:3, 3].copy())
                        now.add(name)
                    T = T @ homogeneous(axis_rotation(axis, angle), np.zeros(3))
                poses[child] = T
                for mover in now:
                    below[mover].add(child)
                stack.append((child, frozenset(now)))
        return poses, axes, below

    def torques(self, q: np.ndarray, base: np.ndarray, gravity: np.ndarray,
                wrench: np.ndarray, point: np.ndarray) -> np.ndarray:
        """Joint torques [N m] that hold the chain at ``q`` (root to tip)."""
        poses, axes, below = self._walk(dict(zip(self.moving, q, strict=True)), base)
        out = np.zeros(len(self.moving))
        for k, name in enumerate(self.moving):
            a, o = axes[name]
            for link in below[name]:
                if link not in self.mass:
                    continue
                m, xyz = self.mass[link]
                c = (poses[link] @ np.r_[xyz, 1.0])[:3]
                out[k] += m * np.cross(a, c - o) @ (-gravity)
            out[k] += a @ (wrench[3:] + np.cross(point - o, wrench[:3]))
        return out
