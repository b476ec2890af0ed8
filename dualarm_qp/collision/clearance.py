"""The clearance of a recorded motion: every pair's distance at every sample.

A run's collision avoidance is judged on what the arms did, not on what the step asked:
from the recorded joints and grasp coordinates, each sample's bodies are placed (the
object by the leader's tool and its grasp) and every pair of the scene is measured.
The smallest distance of each group of pairs (``arm_arm``, ``arm_object``, ``obstacle``,
``self``) and the nearest pair are what ``trajectory.csv`` records; the run keeps its
clearance when no recorded distance falls below the safety distance by more than
:data:`~dualarm_qp.collision.settings.CLEARANCE_ALLOWANCE`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from .scene import GROUPS, CollisionScene
from .settings import CLEARANCE_ALLOWANCE

if TYPE_CHECKING:
    from ..task.scene import DualArmTask

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class ClearanceHistory:
    """Distances along a recorded motion.

    Attributes
    ----------
    groups : ndarray, shape (k, 4)
        Smallest signed distance [m] of each group of :data:`~.scene.GROUPS` at each
        sample (``inf`` for a group without pairs).
    nearest : ndarray, shape (k,)
        Smallest distance of all pairs at each sample [m].
    pair : list of str
        The nearest pair at each sample.
    """

    groups: FloatArray
    nearest: FloatArray
    pair: list[str]


@dataclass(frozen=True)
class ClearanceReport:
    """A run's smallest clearance against the safety distance.

    Attributes
    ----------
    minimum : float
        Smallest recorded distance [m] (``inf`` without samples or pairs).
    pair : str
        The pair it belongs to.
    sample : int
        Its row of the trace (-1 without samples).
    safety_distance : float
        ``d_s`` [m].
    allowance : float
        How far below ``d_s`` a recorded distance may fall [m].
    enforced : bool
        Whether the step kept the pairs apart (collision avoidance enabled).
    breach_sample : int
        The first row whose distance is below ``d_s - allowance`` (-1: none).
    """

    minimum: float
    pair: str
    sample: int
    safety_distance: float
    allowance: float
    enforced: bool
    breach_sample: int = -1

    @property
    def kept(self) -> bool:
        """Whether every recorded distance stays at or above ``d_s - allowance``."""
        return self.breach_sample < 0

    def as_dict(self) -> dict[str, object]:
        """JSON-ready (SI)."""
        return {"min_m": self.minimum if math.isfinite(self.minimum) else None,
                "pair": self.pair, "sample": self.sample,
                "safety_distance_m": self.safety_distance, "allowance_m": self.allowance,
                "enforced": self.enforced, "kept": self.kept,
                "penetration": bool(self.minimum < 0.0)}


def clearance_history(task: DualArmTask, q_l: FloatArray, q_f: FloatArray,
                      sigma_l: FloatArray | None = None) -> ClearanceHistory:
    """Measure every pair of ``task.scene`` at every recorded sample.

    Parameters
    ----------
    task : DualArmTask
        The task; its scene must not be None.
    q_l, q_f : ndarray, shape (k, n_l), (k, n_f)
        Recorded joints [rad].
    sigma_l : ndarray, shape (k,), optional
        The leader's grasp coordinates [m] (a sliding leader grasp).
    """
    scene = task.scene
    if scene is None:
        raise ValueError("the task has no collision scene")
    k = q_l.shape[0]
    groups = np.full((k, len(GROUPS)), np.inf)
    nearest = np.full(k, np.inf)
    pair = [""] * k
    leader, follower = task.leader, task.follower
    H1 = task.H1
    for i in range(k):
        if task.leader_surface is not None and sigma_l is not None:
            H1 = task.H1_at(float(sigma_l[i]))
        frames = scene.frames(leader.link_frames(q_l[i]), follower.link_frames(q_f[i]),
                              leader.fk(q_l[i]) @ H1)
        groups[i], nearest[i], pair[i] = _groups(scene, frames)
    return ClearanceHistory(groups, nearest, pair)


def _groups(scene: CollisionScene, frames: FloatArray) -> tuple[FloatArray, float, str]:
    m = scene.measure(frames)
    d = m.prox.distance
    out = np.full(len(GROUPS), np.inf)
    if d.size == 0:
        return out, math.inf, ""
    np.minimum.at(out, scene.group_of, d)
    j = int(np.argmin(d))
    return out, float(d[j]), scene.pairs[j].name


def clearance_report(scene: CollisionScene, history: ClearanceHistory) -> ClearanceReport:
    """Return the smallest clearance of a history and its first breach of ``d_s - allowance``."""
    s = scene.settings
    if history.nearest.size == 0 or not np.isfinite(history.nearest).any():
        return ClearanceReport(math.inf, "", -1, s.safety_distance, CLEARANCE_ALLOWANCE,
                               s.enabled)
    k = int(np.argmin(history.nearest))
    below = np.flatnonzero(history.nearest < s.safety_distance - CLEARANCE_ALLOWANCE)
    return ClearanceReport(float(history.nearest[k]), history.pair[k], k, s.safety_distance,
                           CLEARANCE_ALLOWANCE, s.enabled,
                           int(below[0]) if below.size else -1)


__all__ = ["ClearanceHistory", "ClearanceReport", "clearance_history", "clearance_report"]
