"""The run's collision checks: the path before it, the clearance after it, the blocking pair.

* before the first sample, :func:`clearance_at_start` asks whether a pair is already
  closer than the safety distance at the start (less the allowance of the recorded
  motion's check, which the run would then fail at its first sample), and
  :func:`path_collision_of` whether ``D(t)`` itself brings the object into an obstacle
  (:mod:`dualarm_qp.collision.path`);
* after the last, :func:`record_clearance` measures every pair at every recorded
  sample, writes the trace's ``clearance_*`` columns and reports the smallest distance
  (:mod:`dualarm_qp.collision.clearance`);
* a run that stalled, ran out of time or found no step is re-read by
  :func:`blocked_by_pair`: when a collision row is what stops the task at the failing
  state, the failure becomes criterion ``"collision"``, naming the pair and its
  distance.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..collision.clearance import ClearanceReport, clearance_history, clearance_report
from ..collision.path import PathCollision, path_collision
from ..collision.settings import CLEARANCE_ALLOWANCE
from ..errors import DualArmError
from ..solvers._scale import max_task_scale
from ..step.limits.collision import ROW_PREFIX
from ..step.state import DualArmState
from ..task.scene import DualArmTask
from .trace import Trace

if TYPE_CHECKING:
    from .controller import DualArmController
    from .failure import Failure

#: A task scale below this at the failing state counts as stopped by its blocking rows
#: (the stall rule's share: a run stalls when its path advances by less than 1% of the
#: time elapsed).
BLOCKED_SCALE = 0.01


@dataclass(frozen=True)
class ClearanceAtStart:
    """A collision pair closer than the safety distance (less the allowance) at the start.

    Attributes
    ----------
    pair : str
        The nearest pair, e.g. ``"follower.link3 - pillar"``.
    distance : float
        Its signed distance at the start [m] (negative: the shapes overlap).
    safety_distance : float
        ``collision.safety_distance`` [m].
    allowance : float
        How far below it a recorded distance may fall [m]
        (:data:`~dualarm_qp.collision.settings.CLEARANCE_ALLOWANCE`).
    """

    pair: str
    distance: float
    safety_distance: float
    allowance: float

    @property
    def limit(self) -> float:
        """The smallest distance the recorded motion may have, ``d_s - allowance`` [m]."""
        return self.safety_distance - self.allowance

    @property
    def message(self) -> str:
        """One line for a person."""
        return (f"collision pair {self.pair} is {self.distance * 1e3:.2f} mm apart at the "
                f"start, closer than the safety distance {self.safety_distance * 1e3:.3g} "
                f"mm (less the allowance of {self.allowance * 1e3:.3g} mm): the recorded "
                "motion could not keep it at its first sample; start the arms further from "
                "it (the initial joints, the bases, the path's start), move the obstacle, "
                "or lower collision.safety_distance")


def clearance_at_start(task: DualArmTask, state: DualArmState) -> ClearanceAtStart | None:
    """Return the nearest pair closer than ``d_s - allowance`` at ``state``, or None.

    Only with collision avoidance on (otherwise the clearance is measured, not kept).
    """
    scene = task.scene
    if scene is None or not scene.settings.enabled:
        return None
    sigma_l = (np.array([state.sigma_leader]) if task.leader_surface is not None else None)
    history = clearance_history(task, state.q_l[None, :], state.q_f[None, :], sigma_l)
    d = float(history.nearest[0])
    s = scene.settings
    if not d < s.safety_distance - CLEARANCE_ALLOWANCE:
        return None
    return ClearanceAtStart(history.pair[0], d, s.safety_distance, CLEARANCE_ALLOWANCE)


def path_collision_of(task: DualArmTask, t0: float, t1: float, dt: float
                      ) -> PathCollision | None:
    """Return where ``D(t)`` brings the object within ``d_s`` of an obstacle, or None.

    Only with collision avoidance on.
    """
    scene = task.scene
    if scene is None or not scene.settings.enabled:
        return None
    return path_collision(scene, task.trajectory, t0, t1, dt)


def record_clearance(task: DualArmTask, trace: Trace) -> ClearanceReport | None:
    """Measure the recorded motion's clearance into ``trace``; its report (None: no scene)."""
    scene = task.scene
    if scene is None:
        return None
    sigma_l = trace.grasp_leader if task.leader_surface is not None else None
    history = clearance_history(task, trace.q_l, trace.q_f, sigma_l)
    g = history.groups
    trace.clearance_arm_arm[:] = g[:, 0]
    trace.clearance_arm_object[:] = g[:, 1]
    trace.clearance_obstacles[:] = g[:, 2]
    trace.clearance_self[:] = g[:, 3]
    trace.clearance_pair[:] = history.pair
    return clearance_report(scene, history)


def blocked_by_pair(controller: DualArmController, trace: Trace, failure: Failure) -> Failure:
    """Return ``failure`` as criterion ``"collision"`` when a collision row stops the task.

    The failure's sample is posed again: when its largest feasible task scale is below
    :data:`BLOCKED_SCALE` and collision rows block it, the message names the pair and
    its distance. Otherwise ``failure`` is returned unchanged.
    """
    scene = controller.task.scene
    if scene is None or not scene.settings.enabled:
        return failure
    k = min(failure.sample, len(trace) - 1)
    state = trace.state(k)
    try:
        problem = controller.builder.build(state).problem
    except DualArmError:
        return failure
    whole = max_task_scale(problem, cap=1.0)
    if whole.scale is not None and whole.scale >= BLOCKED_SCALE:
        return failure
    pairs = [label[len(ROW_PREFIX):] for label in whole.blocking if label.startswith(ROW_PREFIX)]
    if not pairs:
        return failure
    names = scene.pair_names
    distance = {}
    for name in pairs:
        distance[name] = pair_distance(controller, state, names.index(name))
    worst = min(pairs, key=lambda p: distance[p])
    d_s = scene.settings.safety_distance
    why = (f"blocked by a collision pair: {worst} at {distance[worst] * 1e3:.1f} mm "
           f"(safety distance {d_s * 1e3:.1f} mm) stops the path"
           + (f" (also: {', '.join(p for p in pairs if p != worst)})" if len(pairs) > 1
              else ""))
    return dataclasses.replace(failure, criterion="collision", amount=distance[worst],
                               limit=d_s, message=f"{failure.message}; {why}")


def pair_distance(controller: DualArmController, state: DualArmState, pair: int) -> float:
    """Distance [m] of pair ``pair`` of the task's scene at ``state``."""
    task = controller.task
    scene = task.scene
    assert scene is not None
    frames = scene.frames(task.leader.link_frames(state.q_l), task.follower.link_frames(
        state.q_f), task.leader.fk(state.q_l) @ task.H1_at(state.sigma_leader))
    sub = scene.subset([pair])
    return float(np.asarray(sub.measure(frames).prox.distance)[0])


__all__ = ["BLOCKED_SCALE", "ClearanceAtStart", "blocked_by_pair", "clearance_at_start",
           "pair_distance", "path_collision_of", "record_clearance"]
