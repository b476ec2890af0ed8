"""Check the RECORDED clearance of a run from ``trajectory.csv``, independently of the library.

What is an input, read from the built experiment (like the limits in :mod:`csv_check`):
the scene's bodies (each shape in the frame of its link, of the object or of the world),
the pairs the run keeps apart and their groups, the safety distance ``d_s`` and whether
collision avoidance is enabled (``task.scene.settings``), the stated allowance
(``CLEARANCE_ALLOWANCE``), the arms' DH tables or robot files, bases and tools, ``H1`` and
the leader's grasp surface.

What is recomputed: every link frame from the CSV's joints with the tests' own forward
kinematics (:mod:`oracle` / :mod:`dh_oracle` for DH arms, :mod:`urdf_oracle` for URDF
arms), the object's pose from the leader's tool, and every pair's signed distance with
:mod:`clearance_oracle` (not coal, not ``dualarm_qp.geometry``).

Checks (each returns human-readable violations; empty: the rule holds):

* :func:`check_kept`: with collision avoidance enabled, no recorded distance of any pair
  falls below ``d_s - allowance``;
* :func:`check_columns`: the CSV's ``clearance_*`` columns are each group's smallest
  distance (to :data:`COLUMN_TOL`), and ``clearance_pair`` names the nearest pair;
* :func:`penetrations`: the pairs whose shapes overlap at some row (what a run without
  collision avoidance is caught by).

Config owners: ``check_clearance(read_trajectory(csv), exp)`` is (a) + (b) in one call,
``penetrations(recompute(traj, exp))`` the overlaps of a run with collisions disabled.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any

import dh_oracle
import numpy as np
from clearance_oracle import Placed, signed_distance
from oracle import ROWS, inv_pose, is_puma
from urdf_oracle import TURNING, UrdfChain

from dualarm_qp.collision.settings import CLEARANCE_ALLOWANCE
from dualarm_qp.kinematics.robots import example_robot_urdf

#: |CSV clearance - recomputed| allowed [m].
COLUMN_TOL = 1e-6
#: The CSV column of each group of pairs.
COLUMNS = {"arm_arm": "clearance_arm_arm", "arm_object": "clearance_arm_object",
           "obstacle": "clearance_obstacles", "self": "clearance_self"}


def _joints(traj: dict[str, np.ndarray], prefix: str) -> np.ndarray:
    """The CSV's joint columns ``<prefix>1..`` in order, as (rows, n)."""
    found = sorted((int(m.group(1)), c) for c in traj
                   if (m := re.fullmatch(rf"{prefix}(\d+)", c)))
    return np.column_stack([traj[c] for _, c in found])


# ------------------------------------------------------------------ kinematics (oracles)
def frames_function(arm: Any):
    """Return ``q -> world poses of the arm's link frames 0..n and of its tool``.

    Frame 0 is the base, frame i the frame joint i moves (the library's
    ``link_frames`` rows): DH frame i for a DH arm (the PUMA 560 from Table 1 itself),
    the frame of joint i for a URDF arm (:class:`urdf_oracle.UrdfChain`).
    """
    base, tool = np.asarray(arm.base, dtype=float), np.asarray(arm.tool, dtype=float)
    if arm.dh is not None:
        dh = arm.dh
        rows = ROWS if is_puma(arm) else np.column_stack([dh.a, dh.alpha, dh.d, dh.offset])

        def dh_frames(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            F = dh_oracle.frames(rows, q, dh.convention, base)
            return F, F[-1] @ tool

        return dh_frames
    kind, _, rest = arm.source.partition(":")
    where, _, chain_text = rest.rpartition(" ")
    root, _, tip = chain_text.partition("->")
    if kind == "example_robot":
        file = example_robot_urdf(where)
    elif kind == "urdf":
        file = where
    else:
        raise ValueError(f"{arm.name}: no robot file to read ({arm.source!r})")
    chain = UrdfChain(file, root, tip)
    moving = [i for i, j in enumerate(chain.joints) if j.kind in TURNING]

    def urdf_frames(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        all_frames = chain.frames(q, base)
        F = np.array([base, *(all_frames[i] for i in moving)])
        return F, all_frames[-1] @ tool

    return urdf_frames


# ------------------------------------------------------------------ recomputed distances
@dataclass
class Recomputed:
    """Every pair's signed distance at every recorded row.

    Attributes
    ----------
    pairs : list of str
        Pair names (``leader.link2 - pillar``), in the scene's order.
    groups : list of str
        Each pair's group (``arm_arm``, ``arm_object``, ``obstacle``, ``self``).
    distance : ndarray, shape (rows, pairs)
        Signed distances [m].
    t : ndarray, shape (rows,)
        The rows' times [s].
    """

    pairs: list[str]
    groups: list[str]
    distance: np.ndarray
    t: np.ndarray

    def group_min(self, group: str) -> np.ndarray:
        """Smallest distance of ``group`` at each row (``inf`` without pairs)."""
        idx = [i for i, g in enumerate(self.groups) if g == group]
        if not idx:
            return np.full(len(self.t), np.inf)
        return self.distance[:, idx].min(axis=1)

    def nearest(self) -> tuple[np.ndarray, list[str]]:
        """Smallest distance of all pairs at each row, and its pair."""
        if not self.pairs:
            return np.full(len(self.t), np.inf), [""] * len(self.t)
        j = np.argmin(self.distance, axis=1)
        return self.distance[np.arange(len(j)), j], [self.pairs[i] for i in j]


def _placed_bodies(scene: Any, frames: dict[str, np.ndarray]) -> list[Placed]:
    """Each body of ``scene`` placed at every row: ``frames[owner]`` (rows, [links,] 4, 4)."""
    out = []
    for body in scene.bodies:
        T = frames[body.owner]
        if body.owner in ("leader", "follower"):
            T = T[:, body.link]
        shape = body.shape
        R, p = T[:, :3, :3], T[:, :3, 3]
        if hasattr(shape, "radius"):
            a = np.einsum("kij,j->ki", R, np.asarray(shape.a)) + p
            b = np.einsum("kij,j->ki", R, np.asarray(shape.b)) + p
            out.append(Placed("capsule", a=a, b=b, radius=np.full(len(p), shape.radius)))
        else:
            W = T @ np.asarray(shape.pose)
            out.append(Placed("box", centre=W[:, :3, 3], R=W[:, :3, :3],
                              half=np.tile(np.asarray(shape.size) / 2.0, (len(p), 1))))
    return out


def recompute(traj: dict[str, np.ndarray], exp: Any) -> Recomputed:
    """Every pair's signed distance at every row of ``traj``, from its joints alone.

    Raises
    ------
    ValueError
        The experiment has no collision scene.
    """
    task = exp.task
    scene = task.scene
    if scene is None:
        raise ValueError("the experiment has no collision scene")
    rows = len(traj["t"])
    names, groups = [p.name for p in scene.pairs], [p.group for p in scene.pairs]
    if rows == 0:
        return Recomputed(names, groups, np.empty((0, len(names))), np.empty(0))
    q_l, q_f = _joints(traj, "ql"), _joints(traj, "qf")
    leader, follower = frames_function(task.leader), frames_function(task.follower)
    F_l, F_f, T_obj = [], [], []
    for k in range(rows):
        links, tool = leader(q_l[k])
        F_l.append(links)
        F_f.append(follower(q_f[k])[0])
        if task.leader_surface is not None:
            H1 = inv_pose(task.leader_surface.pose(float(traj["grasp_leader"][k])))
        else:
            H1 = np.asarray(task.H1, dtype=float)
        T_obj.append(tool @ H1)
    frames = {"leader": np.array(F_l).reshape(rows, -1, 4, 4),
              "follower": np.array(F_f).reshape(rows, -1, 4, 4),
              "object": np.array(T_obj).reshape(rows, 4, 4),
              "world": np.tile(np.eye(4), (rows, 1, 1))}
    placed = _placed_bodies(scene, frames)
    distance = np.empty((rows, len(scene.pairs)))
    by_kind: dict[tuple[str, str], list[int]] = {}
    for j, pair in enumerate(scene.pairs):
        by_kind.setdefault((placed[pair.a].kind, placed[pair.b].kind), []).append(j)
    for js in by_kind.values():  # every pair of one kind of shapes in one call
        x = Placed.concat([placed[scene.pairs[j].a] for j in js])
        y = Placed.concat([placed[scene.pairs[j].b] for j in js])
        distance[:, js] = signed_distance(x, y).reshape(len(js), rows).T
    return Recomputed(names, groups, distance, np.asarray(traj["t"], dtype=float))


# ------------------------------------------------------------------ checks
def check_kept(rec: Recomputed, safety_distance: float,
               allowance: float = CLEARANCE_ALLOWANCE) -> list[str]:
    """(a) Every pair's recorded distance >= ``safety_distance - allowance``."""
    floor = safety_distance - allowance
    out = []
    for j, name in enumerate(rec.pairs):
        d = rec.distance[:, j]
        bad = np.flatnonzero(d < floor)
        if bad.size:
            k = int(bad[np.argmin(d[bad])])
            out.append(f"clearance {name}: {bad.size} rows below d_s - allowance = "
                       f"{floor * 1e3:.6g} mm; worst row {k} (t={rec.t[k]:.6g} s): "
                       f"{d[k] * 1e3:.6g} mm")
    return out


def check_columns(traj: dict[str, np.ndarray], rec: Recomputed,
                  tol: float = COLUMN_TOL) -> list[str]:
    """(b) The CSV's ``clearance_*`` columns and ``clearance_pair`` match ``rec``."""
    out = []
    for group, column in COLUMNS.items():
        mine = rec.group_min(group)
        if column not in traj:
            if group == "self" and not np.isfinite(mine).any():
                continue  # the column is written for arms with self pairs only
            out.append(f"missing column {column}")
            continue
        csv = traj[column]
        if csv.dtype == object:
            out.append(f"column {column} is not numeric")
            continue
        both_inf = np.isinf(csv) & np.isinf(mine) & (np.sign(csv) == np.sign(mine))
        with np.errstate(invalid="ignore"):
            err = np.where(both_inf, 0.0, np.abs(csv - mine))
        err = np.where(np.isnan(err), np.inf, err)
        bad = np.flatnonzero(err > tol)
        if bad.size:
            k = int(bad[np.argmax(err[bad])])
            out.append(f"{column}: {bad.size} rows differ from the recomputed distance by "
                       f"more than {tol:g} m; worst row {k} (t={rec.t[k]:.6g} s): CSV "
                       f"{csv[k]!r}, recomputed {mine[k]!r}")
    if "clearance_pair" not in traj:
        return [*out, "missing column clearance_pair"]
    nearest, _ = rec.nearest()
    index = {name: j for j, name in enumerate(rec.pairs)}
    wrong = []
    for k, name in enumerate(traj["clearance_pair"].tolist()):
        name = str(name)
        j = index.get(name)
        # Another pair within the tolerance of the nearest one may be named (a tie).
        if j is None or rec.distance[k, j] > nearest[k] + tol:
            wrong.append(k)
    if wrong:
        k = wrong[0]
        out.append(f"clearance_pair: {len(wrong)} rows name a pair that is not the nearest; "
                   f"first row {k}: {traj['clearance_pair'][k]!r}, nearest "
                   f"{rec.nearest()[1][k]!r} at {nearest[k] * 1e3:.6g} mm")
    return out


def penetrations(rec: Recomputed) -> list[str]:
    """(c) Pairs whose shapes overlap (signed distance < 0) at some row."""
    out = []
    for j, name in enumerate(rec.pairs):
        d = rec.distance[:, j]
        bad = np.flatnonzero(d < 0.0)
        if bad.size:
            k = int(bad[np.argmin(d[bad])])
            out.append(f"penetration {name}: {bad.size} rows overlap; deepest row {k} "
                       f"(t={rec.t[k]:.6g} s): {d[k] * 1e3:.6g} mm")
    return out


def check_clearance(traj: dict[str, np.ndarray], exp: Any) -> list[str]:
    """(b), and (a) when the experiment enables collision avoidance; [] without a scene."""
    scene = exp.task.scene
    if scene is None:
        return []
    rec = recompute(traj, exp)
    out = check_columns(traj, rec)
    if scene.settings.enabled:
        out += check_kept(rec, scene.settings.safety_distance)
    return out
