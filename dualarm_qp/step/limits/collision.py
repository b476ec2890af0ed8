"""Collision avoidance: one row per pair of bodies closer than the influence distance.

For a pair of the task's collision scene (:class:`~dualarm_qp.collision.CollisionScene`)
at signed distance ``d < d_i``, with witness points ``p_a`` on body a and ``p_b`` on
body b and the unit normal ``n`` from a to b, the distance changes at

    d_dot = n . (v_b(p_b) - v_a(p_a)) = n^T (J_b(p_b) - J_a(p_a)) x

where ``J(p)`` maps the decision vector ``x`` to the velocity of the point ``p`` fixed to
its body: a leader link moves with the leader's joints, a follower link with the
follower's, the object with the leader's joints and every sliding grasp (its column of
the carried-object model, :class:`~dualarm_qp.task.carry.CarryModel`), an obstacle not
at all. The velocity damper (:mod:`dualarm_qp.collision.settings`) asks

    d_dot >= -xi (d - d_s) / (d_i - d_s),

written as the row ``n^T (J_a - J_b) x <= xi (d - d_s) / (d_i - d_s)``. The normal is
never zero, even for touching or overlapping shapes
(:mod:`dualarm_qp.geometry.distance`), so a pair below ``d_s`` keeps a row that pushes
it apart. With ``J_v, J_w`` the linear and angular rows of the frame's Jacobian at its
origin ``o``, ``n^T J(p) = n^T J_v + ((p - o) x n)^T J_w``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ...collision.scene import CollisionScene
from ..context import ArmKinematics, StepContext
from ..layout import Layout
from ..parts import Constraint
from .registry import LimitSetup, register_limit

FloatArray = NDArray[np.float64]

#: Row names of this limit: ``"clearance <pair>"``.
ROW_PREFIX = "clearance "

#: A row whose largest entry is below this [m/s per unit rate] moves nothing.
ZERO_ROW = 1e-12


class CollisionLimit:
    """The velocity damper of every pair of a collision scene within ``d_i``.

    Parameters
    ----------
    scene : CollisionScene
        Bodies, pairs and the damper's distances.
    layout : Layout
        The slices of the decision vector.
    leader_frames, follower_frames : sequence of int
        Model frame ids of each arm's link frames (``SerialArm.link_frame_ids``).
    """

    name = "collision"
    gives_rows = True

    def __init__(self, scene: CollisionScene, layout: Layout, leader_frames: tuple[int, ...],
                 follower_frames: tuple[int, ...]) -> None:
        self.scene = scene
        self.layout = layout
        self._frames = (leader_frames, follower_frames)
        s = scene.settings
        self._gain = s.approach_speed_max / s.band
        self._d_s = s.safety_distance
        self._d_i = s.influence_distance
        self._owner = [b.owner for b in scene.bodies]
        self._link = [b.link for b in scene.bodies]
        self._names = [ROW_PREFIX + p.name for p in scene.pairs]

    def frames(self, ctx: StepContext) -> FloatArray:
        """Return the scene's frame stack at this step (:meth:`CollisionScene.frames`)."""
        lf, ff = self._frames
        leader = ctx.leader_arm.frame_poses(lf)
        follower = ctx.follower_arm.frame_poses(ff)
        return self.scene.frames(leader, follower, ctx.carry.T_object)

    def constraint(self, ctx: StepContext) -> Constraint:
        """Return one row per pair closer than ``d_i`` (none when every pair is farther)."""
        frames = self.frames(ctx)
        measured = self.scene.measure(frames, within=self._d_i)
        prox = measured.prox
        near = np.flatnonzero(prox.distance < self._d_i)
        if near.size == 0:
            return Constraint()
        lay = self.layout
        G = np.zeros((near.size, lay.n))
        cache: dict[tuple[str, int], FloatArray] = {}
        pairs = self.scene.pairs
        names = []
        for row, j in enumerate(near.tolist()):
            pair = pairs[int(measured.pairs[j])]
            n = prox.normal[j]
            # n^T (J_a - J_b) x <= h
            self._add(G[row], pair.a, prox.point_a[j], n, 1.0, ctx, frames, cache)
            self._add(G[row], pair.b, prox.point_b[j], n, -1.0, ctx, frames, cache)
            names.append(self._names[int(measured.pairs[j])])
        h = self._gain * (prox.distance[near] - self._d_s)
        # A pair that no variable moves at this state (a sphere on its joint's axis
        # against an obstacle) has a zero row: no step changes its distance to first
        # order, so the row is left out (with h < 0 it would only make the step
        # infeasible; the recorded clearance still judges the run).
        moving = np.abs(G).max(axis=1) > ZERO_ROW
        if not moving.all():
            G, h = G[moving], h[moving]
            names = [n for n, m in zip(names, moving.tolist(), strict=True) if m]
        return Constraint(G=G, h=h, row_names=tuple(names))

    def _add(self, row: FloatArray, body: int, point: FloatArray, n: FloatArray, sign: float,
             ctx: StepContext, frames: FloatArray,
             cache: dict[tuple[str, int], FloatArray]) -> None:
        """Add ``sign n^T J(point)`` of ``body`` to ``row``."""
        owner = self._owner[body]
        if owner == "world":
            return
        lay = self.layout
        if owner == "object":
            key = ("object", 0)
            J = ctx.carry.J_object
            origin = ctx.carry.T_object[:3, 3]
            cols = np.r_[np.arange(lay.n_l), np.arange(lay.grasps.start, lay.grasps.stop)]
        else:
            link = self._link[body]
            leader = owner == "leader"
            arm: ArmKinematics = ctx.leader_arm if leader else ctx.follower_arm
            frame = self._frames[0 if leader else 1][link]
            key = (owner, link)
            cached = cache.get(key)
            if cached is None:
                cached = cache[key] = arm.frame_jacobian(frame)
            J = cached
            origin = frames[link if leader else lay.n_l + 1 + link, :3, 3]
            sl = lay.leader if leader else lay.follower
            cols = np.arange(sl.start, sl.stop)
        r = point - origin
        w = np.array([r[1] * n[2] - r[2] * n[1], r[2] * n[0] - r[0] * n[2],
                      r[0] * n[1] - r[1] * n[0]])
        row[cols] += sign * (n @ J[:3] + w @ J[3:])


def _collision(setup: LimitSetup) -> CollisionLimit | None:
    scene = setup.task.scene
    if scene is None or not scene.settings.enabled:
        return None
    scene.settings.check_dt(setup.options.dt)
    task = setup.task
    return CollisionLimit(scene, setup.layout, task.leader.link_frame_ids,
                          task.follower.link_frame_ids)


register_limit("collision", _collision)

__all__ = ["ROW_PREFIX", "CollisionLimit"]
