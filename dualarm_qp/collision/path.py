"""Before a run: the desired path must not bring the object into an obstacle.

The object follows ``D(t)``; if the object's shape placed at ``D(t)`` comes closer to an
obstacle than the safety distance at some ``t``, no motion of the arms can keep the
clearance while following the path, and the run is refused before it starts
(criterion ``"path_collision"``). The path is sampled at the controller's ``dt`` (at
most :data:`MAX_SAMPLES` samples, and its waypoints).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..task.trajectory import Trajectory, WaypointTrajectory
from .scene import CollisionScene

FloatArray = NDArray[np.float64]

#: Most path samples the check measures.
MAX_SAMPLES = 20_000


@dataclass(frozen=True)
class PathCollision:
    """Where the desired path brings the object too close to an obstacle.

    Attributes
    ----------
    obstacle : str
        The obstacle's name.
    t : float
        Path time [s] of the first sample closer than the safety distance.
    distance : float
        Signed distance there [m] (negative: the object is inside the obstacle).
    safety_distance : float
        ``d_s`` [m].
    """

    obstacle: str
    t: float
    distance: float
    safety_distance: float

    @property
    def message(self) -> str:
        """One line for a person."""
        inside = ("runs the object into" if self.distance < 0
                  else "brings the object within the safety distance of")
        return (f"the desired path {inside} obstacle '{self.obstacle}' at t = {self.t:.4g} s "
                f"(distance {self.distance * 1e3:.1f} mm, safety distance "
                f"{self.safety_distance * 1e3:.1f} mm): no motion of the arms can follow it")


def path_collision(scene: CollisionScene, trajectory: Trajectory, t0: float, t1: float,
                   dt: float) -> PathCollision | None:
    """Return the first sample of ``D(t)`` where the object is within ``d_s`` of an obstacle.

    The path is sampled over ``[t0, t1]``; None when no sample is that close.

    Parameters
    ----------
    scene : CollisionScene
        The scene (its object body and obstacles; none of either: None).
    trajectory : Trajectory
        ``D(t)``.
    t0, t1 : float
        Path times of the run [s].
    dt : float
        Sampling interval [s].
    """
    names = scene.body_names
    if "object" not in names:
        return None
    obj = names.index("object")
    pairs = [i for i, p in enumerate(scene.pairs)
             if p.group == "obstacle" and obj in (p.a, p.b)]
    if not pairs:
        return None
    count = int(min(MAX_SAMPLES, max(2, np.ceil((t1 - t0) / dt) + 1)))
    times = np.linspace(t0, t1, count)
    if isinstance(trajectory, WaypointTrajectory):
        knots = np.asarray(trajectory.times, dtype=float)
        times = np.union1d(times, knots[(knots >= t0) & (knots <= t1)])
    sub = scene.subset(pairs)
    n_l, n_f = scene.n_frames
    frames = np.tile(np.eye(4), (n_l + n_f + 2, 1, 1))
    d_s = scene.settings.safety_distance
    for t in times.tolist():
        frames[n_l + n_f] = trajectory.pose(t)
        prox = sub.measure(frames).prox
        close = np.flatnonzero(prox.distance < d_s)
        if close.size:
            j = int(close[np.argmin(prox.distance[close])])
            pair = sub.pairs[j]
            other = pair.b if pair.a == obj else pair.a
            return PathCollision(names[other], float(t), float(prox.distance[j]), d_s)
    return None


__all__ = ["MAX_SAMPLES", "PathCollision", "path_collision"]
