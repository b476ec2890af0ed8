"""The stream of a run: what a bag, a live view and the ROS 2 node publish, per sample.

One :class:`Sample` per recorded row (``trajectory.csv``, or a drive's
:class:`~dualarm_qp.control.trace.Trace` as it is recorded) gives, on the run's clock
``t``:

* **the joints**: both arms' recorded joints and the grasp coordinate(s) as virtual
  joints (:class:`StreamNames`: the joint names of the file's ``cell:`` section, or
  ``leader_joint1 ..``, ``follower_joint1 ..``; the grasps ``follower_grasp`` and, when
  the leader's grasp slides, ``leader_grasp``), with the row's commanded rates as their
  velocities [rad/s, m/s];
* **the frames** (:func:`frames`): the object carried by the leader's recorded joints
  (``world -> object``), the desired object path ``D(path_t)`` (``world ->
  object_target``) and the follower's grasp point on the object (``object ->
  follower_grasp``);
* **the status**: the step's status as a diagnostic level (:func:`diagnostic_level`)
  with the errors the run judges.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..control.trace import Trace
from ..errors import InvalidInputError
from ..task.scene import DualArmTask

FloatArray = NDArray[np.float64]

#: The fixed frame of every transform.
WORLD_FRAME = "world"
#: The object as the leader carries it, and the path's pose of it.
OBJECT_FRAME = "object"
TARGET_FRAME = "object_target"
#: The follower's grasp point on the object (a child of :data:`OBJECT_FRAME`).
GRASP_FRAME = "follower_grasp"

#: Statuses of a step that keeps the task as asked (diagnostic level OK).
OK_STATUSES = frozenset({"optimal", "feasible"})
#: Statuses of a step that failed (diagnostic level ERROR); any other (slowed, relaxed,
#: recovering, escaping, stopping) is a warning.
ERROR_STATUSES = frozenset({"violation", "infeasible", "error"})

#: Diagnostic levels (``diagnostic_msgs/DiagnosticStatus``).
OK, WARN, ERROR = 0, 1, 2

#: The values each diagnostic status carries, in order: columns of ``trajectory.csv``.
DIAGNOSTIC_KEYS = ("path_t", "scale", "grasp", "closure_pos_err", "closure_rot_err",
                   "leader_pos_err", "leader_rot_err")


def diagnostic_level(status: str) -> int:
    """Return the diagnostic level of a step's status (OK, WARN or ERROR)."""
    if status in OK_STATUSES:
        return OK
    return ERROR if status in ERROR_STATUSES else WARN


@dataclass(frozen=True)
class StreamNames:
    """The names the stream gives the joints.

    Attributes
    ----------
    leader, follower : tuple of str
        Each arm's joint names, in the arm's order.
    grasps : tuple of str
        The virtual grasp joints: the follower's, then the leader's when it slides.
    """

    leader: tuple[str, ...]
    follower: tuple[str, ...]
    grasps: tuple[str, ...]

    @property
    def joints(self) -> tuple[str, ...]:
        """Every name of a joint state, in order: leader, follower, grasps."""
        return self.leader + self.follower + self.grasps

    @classmethod
    def of(cls, task: DualArmTask, leader: Sequence[str] | None = None,
           follower: Sequence[str] | None = None, *, path: str = "") -> StreamNames:
        """Return the names for ``task``'s arms (the given ones, or numbered ones).

        Raises
        ------
        InvalidInputError
            A list of names whose length is not its arm's joint count.
        """
        names = []
        for role, arm, given in (("leader", task.leader, leader),
                                 ("follower", task.follower, follower)):
            if given is None:
                names.append(tuple(f"{role}_joint{j + 1}" for j in range(arm.n)))
                continue
            if len(given) != arm.n:
                raise InvalidInputError(f"{path}: cell.{role}.joints: {len(given)} names for "
                                        f"an arm of {arm.n} joints")
            names.append(tuple(given))
        grasps = (GRASP_FRAME,) if task.leader_surface is None else (GRASP_FRAME,
                                                                     "leader_grasp")
        return cls(names[0], names[1], grasps)


@dataclass(frozen=True)
class Sample:
    """One recorded row of a run (SI units).

    Attributes
    ----------
    t : float
        The row's time [s] (``trajectory.csv``'s ``t``).
    path_t : float
        The path time ``D`` was at [s].
    q_l, q_f : ndarray
        Both arms' joints [rad].
    grasp, grasp_leader : float
        The follower's grasp coordinate [m]; the leader's (NaN: it grasps rigidly).
    ql_dot, qf_dot : ndarray
        The rates commanded at the row [rad/s].
    m, m_leader : float
        The grasps' sliding speeds commanded [m/s] (``m_leader`` NaN: rigid).
    status : str
        The step's status.
    values : dict
        :data:`DIAGNOSTIC_KEYS` by name.
    """

    t: float
    path_t: float
    q_l: FloatArray
    q_f: FloatArray
    grasp: float
    grasp_leader: float
    ql_dot: FloatArray
    qf_dot: FloatArray
    m: float
    m_leader: float
    status: str
    values: dict[str, float]

    @property
    def stamp_ns(self) -> int:
        """The row's time in integer nanoseconds (a bag's and a message header's)."""
        return round(self.t * 1e9)

    def positions(self, n_grasps: int) -> FloatArray:
        """Joint-state positions: leader, follower, then the grasps [rad, m]."""
        grasps = [self.grasp, self.grasp_leader][:n_grasps]
        return np.concatenate([self.q_l, self.q_f, np.asarray(grasps, dtype=np.float64)])

    def velocities(self, n_grasps: int) -> FloatArray:
        """Joint-state velocities: the commanded rates [rad/s, m/s], in the same order."""
        rates = [self.m, self.m_leader][:n_grasps]
        return np.concatenate([self.ql_dot, self.qf_dot, np.asarray(rates, dtype=np.float64)])

    @classmethod
    def from_trace(cls, trace: Trace, k: int) -> Sample:
        """Return row ``k`` of a trace (a drive's, as it is recorded)."""
        cols = {"path_t": trace.tau, "scale": trace.scale, "grasp": trace.grasp,
                "closure_pos_err": trace.closure_pos_err,
                "closure_rot_err": trace.closure_rot_err,
                "leader_pos_err": trace.leader_pos_err, "leader_rot_err": trace.leader_rot_err}
        return cls(float(trace.t[k]), float(trace.tau[k]), trace.q_l[k].copy(),
                   trace.q_f[k].copy(), float(trace.grasp[k]), float(trace.grasp_leader[k]),
                   trace.ql_dot[k].copy(), trace.qf_dot[k].copy(), float(trace.m[k]),
                   float(trace.m_leader[k]), trace.status[k],
                   {key: float(cols[key][k]) for key in DIAGNOSTIC_KEYS})


def samples_from_columns(columns: Mapping[str, NDArray[Any]], n_l: int, n_f: int
                         ) -> list[Sample]:
    """Return the rows of ``trajectory.csv``'s columns as samples.

    Parameters
    ----------
    columns : mapping
        The columns by header name (:class:`~dualarm_qp.experiments.figures.rundata.RunData`).
    n_l, n_f : int
        The arms' joint counts (the experiment's: checked against the header).

    Raises
    ------
    InvalidInputError
        A column the stream needs is missing.
    """
    need = ["t", "path_t", "grasp", "m", "status", *DIAGNOSTIC_KEYS,
            *(f"ql{j + 1}" for j in range(n_l)), *(f"qf{j + 1}" for j in range(n_f)),
            *(f"ql_dot{j + 1}" for j in range(n_l)), *(f"qf_dot{j + 1}" for j in range(n_f))]
    missing = [c for c in need if c not in columns]
    if missing:
        raise InvalidInputError(f"trajectory.csv has no column {missing[0]!r} (the run's "
                                f"arms have {n_l} and {n_f} joints)")
    rows = len(columns["t"])
    nan = np.full(rows, np.nan)

    def stack(names: list[str]) -> FloatArray:
        return np.column_stack([np.asarray(columns[c], dtype=np.float64) for c in names]
                               ) if names else np.zeros((rows, 0))

    q_l = stack([f"ql{j + 1}" for j in range(n_l)])
    q_f = stack([f"qf{j + 1}" for j in range(n_f)])
    ql_dot = stack([f"ql_dot{j + 1}" for j in range(n_l)])
    qf_dot = stack([f"qf_dot{j + 1}" for j in range(n_f)])
    col = {c: np.asarray(columns[c], dtype=np.float64).tolist()
           for c in ("t", "path_t", "grasp", "m", *DIAGNOSTIC_KEYS)}
    g_l = np.asarray(columns.get("grasp_leader", nan), dtype=np.float64).tolist()
    m_l = np.asarray(columns.get("m_leader", nan), dtype=np.float64).tolist()
    status = [str(v) for v in columns["status"]]
    values = [dict(zip(DIAGNOSTIC_KEYS, row, strict=True))
              for row in zip(*(col[key] for key in DIAGNOSTIC_KEYS), strict=True)]
    return [Sample(col["t"][k], col["path_t"][k], q_l[k], q_f[k], col["grasp"][k], g_l[k],
                   ql_dot[k], qf_dot[k], col["m"][k], m_l[k], status[k], values[k])
            for k in range(rows)]


@dataclass(frozen=True)
class Frames:
    """One sample's transforms (4x4, metres).

    Attributes
    ----------
    world_object : ndarray
        The object as the leader's recorded joints carry it.
    world_target : ndarray
        The desired object pose ``D(path_t)``.
    object_grasp : ndarray
        The follower's grasp frame on the object at the recorded grasp coordinate.
    """

    world_object: FloatArray
    world_target: FloatArray
    object_grasp: FloatArray

    def transforms(self) -> list[tuple[str, str, FloatArray]]:
        """Return ``(parent, child, pose)`` of every transform, in order."""
        return [(WORLD_FRAME, OBJECT_FRAME, self.world_object),
                (WORLD_FRAME, TARGET_FRAME, self.world_target),
                (OBJECT_FRAME, GRASP_FRAME, self.object_grasp)]


def frames(task: DualArmTask, sample: Sample) -> Frames:
    """Return the transforms of ``sample`` (see the module)."""
    sigma_l = sample.grasp_leader if math.isfinite(sample.grasp_leader) else 0.0
    world_object = task.object_pose(sample.q_l, sigma_l)
    sigma = sample.grasp if math.isfinite(sample.grasp) else task.surface.sigma_min
    return Frames(world_object, task.trajectory.pose(sample.path_t), task.surface.pose(sigma))


def quaternion_xyzw(R: FloatArray) -> FloatArray:
    """Return the unit quaternion ``(x, y, z, w)`` of a rotation matrix, ``w >= 0``."""
    import pinocchio as pin

    q = pin.Quaternion(np.asarray(R, dtype=np.float64)).normalized()
    xyzw = np.array([q.x, q.y, q.z, q.w])
    return -xyzw if xyzw[3] < 0 else xyzw


__all__ = ["DIAGNOSTIC_KEYS", "ERROR", "GRASP_FRAME", "OBJECT_FRAME", "OK", "TARGET_FRAME",
           "WARN", "WORLD_FRAME", "Frames", "Sample", "StreamNames", "diagnostic_level",
           "frames", "quaternion_xyzw", "samples_from_columns"]
