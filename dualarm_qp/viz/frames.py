"""The moving part of the 3D view: node poses and joint-limit states, sample by sample.

A run's ``trajectory.csv`` is read by column name (``t``, ``path_t``, ``ql1..``,
``qf1..``, ``grasp``, optional ``status`` and ``scale``), so arms of any joint count
work. For each sample the world pose of every node of :mod:`.scene` (arm frames, tool,
object) is computed with the arms' own forward kinematics and packed as float32
``[x, y, z, qx, qy, qz, qw]`` (metres, unit quaternion), base64-encoded for the page.
With a collision scene, each sample also gets its nearest pair closer than the influence
distance (:mod:`.collision`), measured here rather than in the browser.
"""

from __future__ import annotations

import base64
import csv
import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from ..errors import InvalidInputError
from ..kinematics.arm import SerialArm
from ..task.scene import DualArmTask
from .collision import NearestPair, nearest_pair
from .scene import arm_node_poses

FloatArray = NDArray[np.float64]

#: A joint is *near* its limit within this share of its range of either end.
NEAR_FRACTION = 0.05

#: Joint-limit states as the page colours them.
LIMIT_OK, LIMIT_NEAR, LIMIT_OUTSIDE = 0, 1, 2

#: Most samples put in one animation; longer runs are thinned evenly (first and last kept).
MAX_FRAMES = 2000


@dataclass(frozen=True)
class Timeline:
    """The recorded motion of a run, in SI units.

    Attributes
    ----------
    t : ndarray, shape (K,)
        Sample times [s].
    path_t : ndarray, shape (K,)
        Path time at which ``D(t)`` was read [s] (equals ``t`` unless the task slowed).
    q_l, q_f : ndarray, shape (K, n_l), (K, n_f)
        Leader and follower joints [rad].
    grasp : ndarray, shape (K,)
        Follower grasp coordinate [m].
    status : list of str
        The step status of each sample (empty strings when not recorded).
    scale : ndarray or None, shape (K,)
        Task scale of each sample (1: the path at full speed), when recorded.
    grasp_leader : ndarray or None, shape (K,)
        Leader grasp coordinate [m] when the leader's grasp slides (CSV column
        ``grasp_leader``), else None.
    """

    t: FloatArray
    path_t: FloatArray
    q_l: FloatArray
    q_f: FloatArray
    grasp: FloatArray
    status: list[str]
    scale: FloatArray | None
    grasp_leader: FloatArray | None = None

    def __len__(self) -> int:
        return len(self.t)


def _numbered(header: list[str], prefix: str) -> list[str]:
    """Columns ``prefix1``, ``prefix2``, ... in joint order."""
    cols = [c for c in header if re.fullmatch(rf"{prefix}\d+", c)]
    return sorted(cols, key=lambda c: int(c[len(prefix):]))


def read_timeline(path: str | Path) -> Timeline:
    """Read a run's ``trajectory.csv``.

    Raises
    ------
    InvalidInputError
        The file is missing, empty, lacks a needed column or holds a non-number.
    """
    p = Path(path)
    try:
        with open(p, newline="", encoding="utf-8") as fh:
            rows = list(csv.reader(fh))
    except OSError as err:
        raise InvalidInputError(f"{p}: cannot read the trajectory: "
                                f"{err.strerror or err}") from None
    if len(rows) < 2:
        raise InvalidInputError(f"{p}: no samples (a header and at least one row needed)")
    header = rows[0]
    ql, qf = _numbered(header, "ql"), _numbered(header, "qf")
    missing = [c for c in ("t", "path_t", "grasp") if c not in header]
    missing += [] if ql else ["ql1.."]
    missing += [] if qf else ["qf1.."]
    if missing:
        raise InvalidInputError(f"{p}: missing column(s) {', '.join(missing)} (a "
                                "trajectory.csv written by 'dualarm-qp run' has them)")
    index = {c: i for i, c in enumerate(header)}

    def column(names: list[str]) -> FloatArray:
        try:
            return np.array([[float(r[index[c]]) for c in names] for r in rows[1:]])
        except (ValueError, IndexError) as err:
            raise InvalidInputError(f"{p}: a row of {', '.join(names[:3])} is not a "
                                    f"number ({err})") from None

    status = ([r[index["status"]] if len(r) > index["status"] else "" for r in rows[1:]]
              if "status" in index else [""] * (len(rows) - 1))
    return Timeline(t=column(["t"])[:, 0], path_t=column(["path_t"])[:, 0],
                    q_l=column(ql), q_f=column(qf), grasp=column(["grasp"])[:, 0],
                    status=status,
                    scale=column(["scale"])[:, 0] if "scale" in index else None,
                    grasp_leader=(column(["grasp_leader"])[:, 0] if "grasp_leader" in index
                                  else None))


def limit_states(arm: SerialArm, q: FloatArray) -> NDArray[np.uint8]:
    """Per joint: 0 inside, 1 near a limit (:data:`NEAR_FRACTION`), 2 outside.

    Parameters
    ----------
    arm : SerialArm
        Gives ``q_min`` and ``q_max`` [rad].
    q : ndarray, shape (..., n)
        Joints [rad].
    """
    q = np.asarray(q, dtype=float)
    lo, hi = arm.q_min, arm.q_max
    span = np.where(np.isfinite(hi - lo), hi - lo, np.inf)
    margin = np.minimum(q - lo, hi - q)
    state = np.where(margin < NEAR_FRACTION * span, LIMIT_NEAR, LIMIT_OK)
    state = np.where(margin < 0.0, LIMIT_OUTSIDE, state)
    return state.astype(np.uint8)


def pose7(T: FloatArray) -> list[float]:
    """``[x, y, z, qx, qy, qz, qw]`` of a 4x4 pose (metres, unit quaternion)."""
    quat = pin.Quaternion(np.asarray(T[:3, :3], dtype=float)).coeffs()
    return [*map(float, T[:3, 3]), *map(float, quat)]


def sample_nodes(task: DualArmTask, q_l: Any, q_f: Any, grasp: float,
                 grasp_leader: float = 0.0) -> dict[str, Any]:
    """Return the node poses and limit states of one sample (see :func:`frame_payload`).

    ``grasp_leader`` [m] places the object when the leader's grasp slides
    (``task.leader_surface``); it is ignored otherwise. With a collision scene
    (``task.scene``), ``nearest`` is the nearest pair closer than the influence
    distance, or None (:func:`~dualarm_qp.viz.collision.nearest_pair`).
    """
    q_l = np.asarray(q_l, dtype=float)
    q_f = np.asarray(q_f, dtype=float)
    poses = [arm_node_poses(arm, q) for arm, q in ((task.leader, q_l), (task.follower, q_f))]
    T_obj = task.object_pose(q_l, float(grasp_leader))
    out: dict[str, Any] = {
        "arms": [[pose7(T) for T in nodes] for nodes in poses],
        "limits": [limit_states(task.leader, q_l).tolist(),
                   limit_states(task.follower, q_f).tolist()],
        "object": pose7(T_obj),
        "grasp_local": [float(x) for x in task.surface.point(float(grasp))]}
    if task.scene is not None:  # the arms' link frames are their nodes but the tool
        frames = task.scene.frames(poses[0][:-1], poses[1][:-1], T_obj)
        out["nearest"] = nearest_pair(task.scene, frames)
    return out


def _b64(a: NDArray[Any]) -> str:
    return base64.b64encode(np.ascontiguousarray(a).tobytes()).decode("ascii")


def thin(count: int, most: int = MAX_FRAMES) -> NDArray[np.intp]:
    """Return at most ``most`` evenly spread indices of ``count``, first and last kept."""
    if count <= most:
        return np.arange(count)
    return np.unique(np.round(np.linspace(0, count - 1, most)).astype(np.intp))


def frame_payload(task: DualArmTask, timeline: Timeline) -> dict[str, Any]:
    """Everything the page needs to replay a run, JSON-ready.

    Returns
    -------
    dict
        ``t``, ``path_t``, ``grasp`` [s, s, m], ``scale`` (or None), ``status`` (index
        into ``status_names``), ``nodes`` (base64 float32, per sample the 7 numbers of
        each leader node, then each follower node, then the object), ``limits`` (base64
        uint8, per sample each leader joint then each follower joint), ``grasp_local``
        (base64 float32, the grasp point in object coordinates [m]). With a collision
        scene (``task.scene``), the nearest pair closer than the influence distance
        (:func:`~dualarm_qp.viz.collision.nearest_pair`): ``near_pair`` (its index in
        the scene's pairs, -1 when no pair is that close), ``near_distance`` [m] (None
        when none) and ``near_points`` (base64 float32, per sample its witness points
        on the first and the second body [m], NaN when none).
    """
    n_l, n_f = task.leader.n, task.follower.n
    if timeline.q_l.shape[1] != n_l or timeline.q_f.shape[1] != n_f:
        raise InvalidInputError(
            f"the trajectory has {timeline.q_l.shape[1]} leader and "
            f"{timeline.q_f.shape[1]} follower joints, the task's arms {n_l} and {n_f}")
    keep = thin(len(timeline))
    nodes, limits, local = [], [], []
    nearest: list[NearestPair | None] = []
    lead = timeline.grasp_leader
    for k in keep:
        s = sample_nodes(task, timeline.q_l[k], timeline.q_f[k], timeline.grasp[k],
                         0.0 if lead is None else float(lead[k]))
        nodes.append([v for arm in s["arms"] for pose in arm for v in pose] + s["object"])
        limits.append(s["limits"][0] + s["limits"][1])
        local.append(s["grasp_local"])
        nearest.append(s.get("nearest"))
    names = sorted(set(timeline.status))
    scale = None
    if timeline.scale is not None:
        scale = [round(float(x), 6) if math.isfinite(x) else None
                 for x in timeline.scale[keep]]
    near = nearest_payload(nearest) if task.scene is not None else {}
    return {
        "t": [round(float(x), 6) for x in timeline.t[keep]],
        "path_t": [round(float(x), 6) for x in timeline.path_t[keep]],
        "grasp": [round(float(x), 7) for x in timeline.grasp[keep]],
        "scale": scale,
        "status_names": names,
        "status": [names.index(timeline.status[k]) for k in keep],
        "nodes": _b64(np.array(nodes, dtype="<f4")),
        "limits": _b64(np.array(limits, dtype=np.uint8)),
        "grasp_local": _b64(np.array(local, dtype="<f4")),
        **near,
    }


def nearest_payload(nearest: list[NearestPair | None]) -> dict[str, Any]:
    """Return the nearest pair of each sample, JSON-ready (see :func:`frame_payload`)."""
    points = np.full((len(nearest), 6), np.nan)
    for k, n in enumerate(nearest):
        if n is not None:
            points[k] = np.concatenate([n.point_a, n.point_b])
    return {"near_pair": [-1 if n is None else n.pair for n in nearest],
            "near_distance": [None if n is None else round(n.distance, 7) for n in nearest],
            "near_points": _b64(points.astype("<f4"))}
