"""Before a run: the checks that refuse it before its first sample.

:func:`before_the_run` asks, in order: can the arms reach the path at its waypoints
(``"unreachable"``, below), does a joint need more than its torque limit at the start
(``"torque"``, :mod:`.torques`), is a collision pair closer than the safety distance less
the allowance at the start (``"collision"``), does ``D(t)`` take the object through an
obstacle (``"path_collision"``, :mod:`.collisions`).

**The reach check.**

A path that leaves the arms' reach is found by the run only when it gets there, as a
tracking or closure failure whose cause is hard to read. This check finds it before the
run starts: it walks inverse kinematics along the path, each solve seeded from the one
before (the joints the run would have), and at every waypoint (the waypoints of a
waypoint path; the end of any other path) asks:

* the leader: joints inside its range that put the object at ``D(t)`` (for a sliding
  leader grasp, at some grasp coordinate in the grasp's range);
* the follower: joints inside its range that put its tool on the grasp, at some grasp
  coordinate in the grasp's range (the grasp may slide there during the run).

Joint ranges are kept only for a solver that claims hard limits (the paper's methods
ignore them). A waypoint that fails the seeded solve and the other starts (the seed
nudged by :data:`SEED_NUDGE` on every joint, down for a joint at its upper limit, which
leaves an exact singularity, and the range's middle when the ranges are kept) is
reported as :class:`Unreachable`; the run then fails on criterion ``"unreachable"``
before its first sample. A Case 2 support (the follower's path follows gravity) is
checked for the leader only.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..kinematics.arm import SerialArm
from ..kinematics.ik import ik_dls
from ..step.state import DualArmState
from ..task.scene import DualArmTask
from ..task.trajectory import WaypointTrajectory
from .collisions import clearance_at_start, path_collision_of
from .controller import DualArmController
from .failure import Failure
from .torques import torque_at_start

FloatArray = NDArray[np.float64]

#: Inverse kinematics counts as reaching a pose within these errors [m], [rad].
REACH_TOLERANCE = (1e-6, 1e-6)

#: Path samples between two checked points, solved only to carry the seed along.
SEEDS_PER_SEGMENT = 8

#: Grasp coordinates tried across the grasp's range when the current one fails.
GRASP_CANDIDATES = 9

#: Added to every joint of a seed that fails, for a second try [rad].
SEED_NUDGE = 1e-3


@dataclass(frozen=True)
class Unreachable:
    """A waypoint that an arm cannot reach.

    Attributes
    ----------
    arm : {"leader", "follower"}
        The arm that cannot reach it.
    waypoint : str
        Which point of the path (``"waypoint 2 of the path"``, ``"the end of the path"``).
    t : float
        Path time of that point [s].
    position_error, rotation_error : float
        The smallest errors inverse kinematics reached [m], [rad].
    within_ranges : bool
        Whether the arm's joint ranges were kept (for a solver that claims hard limits).
    """

    arm: str
    waypoint: str
    t: float
    position_error: float
    rotation_error: float
    within_ranges: bool = True

    @property
    def message(self) -> str:
        """One line for a person."""
        ranges = " within its joint ranges" if self.within_ranges else ""
        return (f"the {self.arm} cannot reach {self.waypoint} (t = {self.t:.4g} s){ranges}:"
                f" the closest it gets is {self.position_error:.3g} m"
                f", {self.rotation_error:.3g} rad away")


def checkpoints(task: DualArmTask, t_start: float, t_end: float) -> list[tuple[float, str]]:
    """Return the points of the path the check asks about: ``(path time [s], name)``.

    The waypoints of a waypoint path after its start (named by their index in the
    path, 0 being the start), else the path's end.
    """
    traj = task.trajectory
    if isinstance(traj, WaypointTrajectory):
        return [(float(t), f"waypoint {i} of the path") for i, t in
                enumerate(traj.times.tolist()) if t_start < t <= t_end + 1e-12]
    return [(t_end, "the end of the path")]


def unreachable_waypoint(task: DualArmTask, initial: DualArmState, t_end: float, *,
                         within_ranges: bool) -> Unreachable | None:
    """Walk the path from ``initial`` to ``t_end``; return the first waypoint out of reach.

    Parameters
    ----------
    task : DualArmTask
        Arms, object and path.
    initial : DualArmState
        Where the run starts (the first seeds).
    t_end : float
        Path time at which the run ends [s].
    within_ranges : bool
        Keep the joints inside their ranges (for a solver that claims hard limits).

    Returns
    -------
    Unreachable or None
        None when every waypoint is reached.
    """
    q_l, q_f = initial.q_l.copy(), initial.q_f.copy()
    sigma, sigma_l = float(initial.sigma), float(initial.sigma_leader)
    t_prev = float(initial.t)
    for t_check, name in checkpoints(task, t_prev, t_end):
        for t in np.linspace(t_prev, t_check, SEEDS_PER_SEGMENT + 1)[1:].tolist():
            last = t == t_check
            reached_l = _leader(task, t, q_l, sigma_l, within_ranges)
            if isinstance(reached_l, Unreachable):
                if last:
                    return Unreachable("leader", name, t, reached_l.position_error,
                                       reached_l.rotation_error, within_ranges)
                continue
            q_l, sigma_l = reached_l
            if task.contact is not None:
                continue  # the support's line follows gravity: leader only
            reached_f = _follower(task, q_l, q_f, sigma, sigma_l, within_ranges)
            if isinstance(reached_f, Unreachable):
                if last:
                    return Unreachable("follower", name, t, reached_f.position_error,
                                       reached_f.rotation_error, within_ranges)
                continue
            q_f, sigma = reached_f
        t_prev = t_check
    return None


def _leader(task: DualArmTask, t: float, q: FloatArray, sigma_l: float, within: bool
            ) -> tuple[FloatArray, float] | Unreachable:
    """Leader joints (and grasp coordinate) that put the object at ``D(t)``."""
    lead = task.leader_surface
    sigmas = [sigma_l] if lead is None else _candidates(sigma_l, lead.sigma_min,
                                                        lead.sigma_max)
    best = (np.inf, np.inf)
    for s in sigmas:
        found = _reach(task.leader, task.leader_target(t, s), q, within)
        if isinstance(found, np.ndarray):
            return found, s
        best = min(best, found)
    return Unreachable("leader", "", t, *best)


def _follower(task: DualArmTask, q_l: FloatArray, q: FloatArray, sigma: float,
              sigma_l: float, within: bool) -> tuple[FloatArray, float] | Unreachable:
    """Follower joints and a grasp coordinate that close the grasp."""
    surface = task.surface
    best = (np.inf, np.inf)
    for s in _candidates(sigma, surface.sigma_min, surface.sigma_max):
        found = _reach(task.follower, task.follower_target(q_l, s, sigma_l), q, within)
        if isinstance(found, np.ndarray):
            return found, s
        best = min(best, found)
    return Unreachable("follower", "", 0.0, *best)


def _candidates(current: float, lo: float, hi: float) -> list[float]:
    """Grasp coordinates to try: the current one, then the range nearest first [m]."""
    if not (np.isfinite(lo) and np.isfinite(hi)):
        return [current]
    grid = np.linspace(lo, hi, GRASP_CANDIDATES)
    order = np.argsort(np.abs(grid - current), kind="stable")
    return [current, *(float(grid[i]) for i in order)]


def _reach(arm: SerialArm, T: FloatArray, seed: FloatArray, within: bool
           ) -> FloatArray | tuple[float, float]:
    """Joints reaching ``T`` from ``seed``, from it nudged or from the range's middle.

    Else the smallest errors reached [m], [rad].
    """
    tol_p, tol_r = REACH_TOLERANCE
    best = (np.inf, np.inf)
    # A seed at an exact singularity gives no first-order descent along the direction
    # the arm lost: the nudged seed leaves it deterministically (not by rounding).
    nudged = seed + SEED_NUDGE
    if within:  # a joint on its upper limit is nudged the other way (not clipped back)
        nudged = np.where(nudged <= arm.q_max, nudged, seed - SEED_NUDGE)
    starts = [seed, nudged]
    if within and np.isfinite(arm.q_min).all() and np.isfinite(arm.q_max).all():
        starts.append(0.5 * (arm.q_min + arm.q_max))
    for q0 in starts:
        res = ik_dls(arm, T, q0, tol_pos=tol_p, tol_rot=tol_r, max_iter=200,
                     respect_limits=within, raise_on_failure=False)
        if res.success:
            return res.q
        best = min(best, (res.position_error, res.rotation_error))
    return best


def before_the_run(controller: DualArmController, start: DualArmState, path_end: float
                   ) -> tuple[Failure, dict[str, Any]] | None:
    """Return the failure of a run refused before its first sample, and its record.

    In order: a waypoint out of reach (``"unreachable"``), a joint beyond its torque
    limit at the start (``"torque"``), a collision pair closer than the safety distance
    less the allowance at the start (``"collision"``), a path through an obstacle
    (``"path_collision"``). None when the run may start.
    """
    task, dt, t0 = controller.task, controller.options.dt, float(start.t)
    miss = unreachable_waypoint(task, start, path_end, within_ranges=controller.hard_bounds)
    if miss is not None:
        return (Failure("unreachable", 0, t0, miss.position_error, REACH_TOLERANCE[0],
                        f"before the run: {miss.message}"),
                {"unreachable": {"arm": miss.arm, "waypoint": miss.waypoint, "t_s": miss.t}})
    heavy = torque_at_start(controller, start)
    if heavy is not None:
        return (Failure("torque", 0, t0, heavy.torque, heavy.limit,
                        f"before the run: {heavy.message}"),
                {"torque_at_start": {"joint": heavy.joint, "torque_N_m": heavy.torque,
                                     "limit_N_m": heavy.limit}})
    close = clearance_at_start(task, start)
    if close is not None:
        return (Failure("collision", 0, t0, close.distance, close.limit,
                        f"before the run: {close.message}"),
                {"collision_at_start": {"pair": close.pair, "distance_m": close.distance,
                                        "safety_distance_m": close.safety_distance}})
    blocked = path_collision_of(task, t0, path_end, dt)
    if blocked is not None:
        return (Failure("path_collision", 0, blocked.t, blocked.distance,
                        blocked.safety_distance, f"before the run: {blocked.message}"),
                {"path_collision": {"obstacle": blocked.obstacle, "t_s": blocked.t,
                                    "distance_m": blocked.distance}})
    return None


__all__ = ["Unreachable", "before_the_run", "checkpoints", "unreachable_waypoint"]
