"""The plan's statics at a measured state, for the plant: its load feed-forward and split.

The MuJoCo plant (:mod:`dualarm_qp.physics.plant`) holds each hand's share of the load by
a feed-forward from the plan's quasi-static split (:func:`load_feedforward`), compares
what its sensors measure with that split (:func:`planned_split`), and may simulate a
follower whose base is off the model's (:func:`simulated_task`, ``physics.base_error``).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from ..control.measured import HandReading, load_share
from ..errors import SupportLostError
from ..step.state import DualArmState
from ..task.hands import hand_statics
from ..task.loads import UnbalancedLoadError, split_load
from ..task.scene import DualArmTask

FloatArray = NDArray[np.float64]


def load_feedforward(task: DualArmTask, state: DualArmState) -> FloatArray:
    """Return the torques [N m] that hold each hand's share of ``task``'s load at ``state``.

    The share is the quasi-static minimum-norm split (:func:`dualarm_qp.task.loads.split_load`)
    at the state (zero where the grasps cannot hold the load), its moment about each
    hand's grasp point (the leader's tool point, the follower's contact point on the
    object). ``J`` is the Jacobian of the tool point, so the moment is moved there first,
    ``m_t = m + (p - t) x f``, and the torque is ``J^T [f; m_t]`` (the follower's contact
    point is its tool point only up to the closure error). The leader's joints first.
    ``task.load`` must be set.
    """
    if task.load is None:
        raise ValueError("the load feed-forward needs a task with a load")
    try:
        hands, T_obj = hand_statics(task, state.q_l, state.sigma, state.sigma_leader)
        split = split_load(hands, task.load, T_obj).wrenches
    except (UnbalancedLoadError, SupportLostError):
        return np.zeros(task.leader.n + task.follower.n)
    parts = []
    for arm, q, w, hand in ((task.leader, state.q_l, split[0], hands[0]),
                            (task.follower, state.q_f, split[1], hands[1])):
        T, J = arm.fk_jacobian(q)
        f, m = w[:3], w[3:]
        parts.append(J.T @ np.r_[f, m + np.cross(hand.point - T[:3, 3], f)])
    return np.concatenate(parts)


def against_plan(task: DualArmTask, state: DualArmState, reading: HandReading,
                 push: FloatArray) -> tuple[float, float]:
    """Return the plan's share of the follower along ``push`` and the measured split's error.

    The error is the larger over the two hands of ``|measured - planned| / |planned|``
    of the force along ``push`` (unit: up, or a support's normal); both NaN where the
    plan has no split.
    """
    planned = planned_split(task, state)
    if planned is None:
        return float("nan"), float("nan")
    share = load_share(planned[0], planned[1], push)
    error = max(_relative(float(w[:3] @ push), float(p[:3] @ push))
                for w, p in zip((reading.leader, reading.follower), planned, strict=True))
    return share, error


def _relative(measured: float, planned: float) -> float:
    """Return ``|measured - planned| / |planned|`` (NaN when the plan carries nothing)."""
    return abs(measured - planned) / abs(planned) if abs(planned) > 1e-9 else float("nan")


def planned_split(task: DualArmTask, state: DualArmState
                  ) -> tuple[FloatArray, FloatArray] | None:
    """Return the plan's split of ``task``'s load at ``state`` (None where it has none)."""
    if task.load is None:
        return None
    try:
        hands, T_obj = hand_statics(task, state.q_l, state.sigma, state.sigma_leader)
        split = split_load(hands, task.load, T_obj).wrenches
    except (UnbalancedLoadError, SupportLostError):
        return None
    return split[0], split[1]


def simulated_task(task: DualArmTask, base_error: FloatArray | None) -> DualArmTask:
    """Return ``task`` with its follower's base off by ``base_error`` (its own frame).

    ``base_error`` is ``[x, y, z]`` [m] and roll, pitch, yaw [rad] (``R = Rz Ry Rx``):
    ``T_base_simulated = T_base [R, p; 0, 1]``. None: ``task`` as it is.
    """
    if base_error is None:
        return task
    error = np.eye(4)
    error[:3, :3] = pin.rpy.rpyToMatrix(*np.asarray(base_error[3:], dtype=float))
    error[:3, 3] = base_error[:3]
    return dataclasses.replace(task, follower=task.follower.with_base(
        np.asarray(task.follower.base) @ error))


__all__ = ["against_plan", "load_feedforward", "planned_split", "simulated_task"]
