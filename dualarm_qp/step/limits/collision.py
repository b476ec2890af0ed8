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

from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..._compiled import kernel
from ...collision.scene import OWNERS, CollisionScene
from ..context import StepContext
from ..layout import Layout
from .registry import LimitSetup, register_limit

FloatArray = NDArray[np.float64]

#: Row names of this limit: ``"clearance <pair>"``.
ROW_PREFIX = "clearance "

#: A row whose largest entry is below this [m/s per unit rate] moves nothing.
ZERO_ROW = 1e-12

#: What a non-finite frame or Jacobian of the rows is called in the error.
NONFINITE = "the collision rows (the scene's frames or the Jacobians)"


class CollisionLimit(kernel.CollisionLimit):
    """The velocity damper of every pair of a collision scene within ``d_i``.

    A compiled part. At each step the kernel computes the frame stack of
    :meth:`frames`, the scene's :meth:`~CollisionScene.measure` within ``d_i``, and for
    each pair closer than ``d_i`` the row ``n^T (J_a - J_b)`` and its bound (the
    kernel's ``DamperScene``). A pair that no variable moves at this state (a sphere on
    its joint's axis against an obstacle) has a zero row (largest entry at most
    :data:`ZERO_ROW`): no step changes its distance to first order, so the row is left
    out (with ``h < 0`` it would only make the step infeasible; the recorded clearance
    still judges the run). A body's frame or a Jacobian the rows read that is not
    finite stops the step with a :class:`~dualarm_qp.errors.NonFiniteError`.

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
        s = scene.settings
        owner = [OWNERS.index(b.owner) for b in scene.bodies]
        frames = (leader_frames, follower_frames)
        model_frame = [frames[OWNERS.index(b.owner)][b.link]
                       if b.owner in ("leader", "follower") else -1 for b in scene.bodies]
        damper = kernel.DamperScene(
            *scene.measured_as(), owner, model_frame, list(leader_frames),
            list(follower_frames), s.influence_distance, s.safety_distance,
            s.approach_speed_max / s.band, ZERO_ROW, layout.n_l, layout.n_f,
            layout.grasps.start, layout.n)
        super().__init__(damper, [ROW_PREFIX + p.name for p in scene.pairs], NONFINITE)
        self._damper = damper
        self._d_i, self._d_s = s.influence_distance, s.safety_distance
        self._gain = s.approach_speed_max / s.band
        self.scene = scene
        self.layout = layout
        self._frames = frames

    def __reduce__(self) -> tuple[Any, ...]:
        return (CollisionLimit, (self.scene, self.layout, *self._frames))

    def frames(self, ctx: StepContext) -> FloatArray:
        """Return the scene's frame stack at this step (:meth:`CollisionScene.frames`)."""
        lf, ff = self._frames
        leader = ctx.leader_arm.frame_poses(lf)
        follower = ctx.follower_arm.frame_poses(ff)
        return self.scene.frames(leader, follower, ctx.carry.T_object)


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
