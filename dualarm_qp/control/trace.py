"""The trace of a rollout: one row per sample, what was realised and what was commanded."""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..step.state import DualArmState
from ..task.scene import DualArmTask
from ..task.surfaces import GraspSurface
from .controller import ControlOutput, DualArmController

FloatArray = NDArray[np.float64]


@dataclass
class Trace:
    """Everything recorded along a rollout, one row per sample.

    Row k holds the realised state at time ``t[k]`` (``tau``, ``q_l``, ``q_f``,
    ``grasp``: what the arms actually did) and the command computed from it
    (``ql_dot``, ``qf_dot``, ``m``: the rates applied over the next sample, already
    scaled); the command of the last row is computed but not integrated. The realised
    rates are the differences of consecutive states over ``dt``; without a
    position-level correction they equal the commanded ones.

    ``kinematics_time_s`` holds both arms and the carried object. ``grasp_leader``,
    ``m_leader`` and ``margin_grasp_leader`` are the leader's sliding grasp (NaN when the
    leader grasps rigidly). ``closure_*_err_pre`` is the grasp closure
    error of the integrated state before any position-level correction (the paper's
    re-resolution, or the drift projection of the paper's methods) made row k's state;
    ``correction_l`` and ``correction_f`` are the largest joint change [rad] that
    correction applied. Both equal the plain values (and 0) when no correction ran.
    ``feedback_pos`` and ``feedback_rot`` are the closure feedback ``K e`` in the
    follower's right-hand side [m/s, rad/s]: the velocity-level correction, which the
    step's limits bound. ``support_force`` is the push ``h`` [N] of a supporting
    follower (Case 2) at the row's state (NaN for a grasp, and for a step that raised).
    ``f_leader`` and ``f_follower`` are the wrench ``[f; m]`` [N, N m] each hand applies
    to the object (world frame, moment about the hand's grasp point) for a task with a
    load, computed from the recorded joints once the run is over
    (:mod:`dualarm_qp.control.loads`; NaN without a load). ``tau_leader`` and
    ``tau_follower`` are each arm's quasi-static joint torques [N m] (its links' weight and
    its hand's share of the load), likewise computed after the run for a task with a
    load or torque limits (:mod:`dualarm_qp.control.torques`; NaN otherwise).

    ``wrench_leader``, ``wrench_follower``, ``internal_force``, ``internal_follower``,
    ``load_share`` and ``object_pose`` are what a plant that measures the hands'
    wrenches measured with each sample's state (:mod:`dualarm_qp.control.measured`; NaN
    without such a plant): each hand's wrench on the object, the size of the internal
    force [N] and the follower's internal wrench, the follower's share of the load, the
    object's pose (position [m], quaternion ``w, x, y, z``); ``torque_ratio_measured``
    the largest share of a joint's torque limit its joints reached over the sample.

    ``clearance_*`` are the smallest signed distances [m] of each group of pairs of the
    task's collision scene at the row's state (``inf`` for a group without pairs; NaN
    without a scene) and ``clearance_pair`` the nearest pair: measured from the recorded
    joints once the run is over (:mod:`dualarm_qp.collision.clearance`).

    ``scale`` is the task scale of the row's step: the share of the path rate asked for
    that the limits allowed (1: not slowed; 0 for a command not applied). The rollout
    asks for full speed, except on the sample where the path ends, which it shortens to
    land on the end (no time is lost there): the path time advances by ``scale *
    min(dt, path end - tau)``. At the path's end the controller is asked for no motion
    and its command is not applied: the last row repeats the task scale of the row
    before, the one at which the path ended.
    """

    t: FloatArray
    tau: FloatArray
    q_l: FloatArray
    q_f: FloatArray
    grasp: FloatArray
    grasp_leader: FloatArray
    m: FloatArray
    m_leader: FloatArray
    ql_dot: FloatArray
    qf_dot: FloatArray
    closure_pos_err: FloatArray
    closure_rot_err: FloatArray
    closure_pos_err_pre: FloatArray
    closure_rot_err_pre: FloatArray
    correction_l: FloatArray
    correction_f: FloatArray
    feedback_pos: FloatArray
    feedback_rot: FloatArray
    leader_pos_err: FloatArray
    leader_rot_err: FloatArray
    sigma_min_l: FloatArray
    sigma_min_f: FloatArray
    margin_qf: FloatArray
    margin_ql: FloatArray
    margin_grasp: FloatArray
    margin_grasp_leader: FloatArray
    scale: FloatArray
    status: list[str]
    fallback: FloatArray
    objective: FloatArray
    eq_residual: FloatArray
    bound_violation: FloatArray
    kinematics_time_s: FloatArray
    assembly_time_s: FloatArray
    solve_time_s: FloatArray
    step_time_s: FloatArray
    support_force: FloatArray
    clearance_arm_arm: FloatArray
    clearance_arm_object: FloatArray
    clearance_obstacles: FloatArray
    clearance_self: FloatArray
    clearance_pair: list[str]
    f_leader: FloatArray
    f_follower: FloatArray
    tau_leader: FloatArray
    tau_follower: FloatArray
    wrench_leader: FloatArray
    wrench_follower: FloatArray
    internal_force: FloatArray
    internal_follower: FloatArray
    load_share: FloatArray
    object_pose: FloatArray
    torque_ratio_measured: FloatArray

    @classmethod
    def allocate(cls, rows: int, n_l: int, n_f: int) -> Trace:
        """Arrays for ``rows`` samples, filled with NaN until written."""
        widths = {"q_l": n_l, "ql_dot": n_l, "margin_ql": n_l,
                  "q_f": n_f, "qf_dot": n_f, "margin_qf": n_f, "f_leader": 6,
                  "f_follower": 6, "tau_leader": n_l, "tau_follower": n_f,
                  "wrench_leader": 6, "wrench_follower": 6, "internal_follower": 6,
                  "object_pose": 7}
        values: dict[str, Any] = {}
        for f in fields(cls):
            if f.name in ("status", "clearance_pair"):
                values[f.name] = [""] * rows
            elif f.name in widths:
                values[f.name] = np.full((rows, widths[f.name]), np.nan)
            else:
                values[f.name] = np.full(rows, np.nan)
        return cls(**values)

    def truncate(self, rows: int) -> Trace:
        """Return the first ``rows`` samples."""
        return Trace(**{f.name: getattr(self, f.name)[:rows] for f in fields(self)})

    def __len__(self) -> int:
        return int(self.t.shape[0])

    def state(self, k: int) -> DualArmState:
        """Return the controller's input at sample ``k`` (clipped to the last sample).

        The path time is the sample's ``tau``; a fixed leader grasp (NaN) is 0.
        """
        k = min(k, len(self) - 1)
        sigma_l = float(self.grasp_leader[k])
        return DualArmState(float(self.tau[k]), self.q_l[k], self.q_f[k],
                            float(self.grasp[k]), sigma_l if math.isfinite(sigma_l) else 0.0)


def record(tr: Trace, k: int, t: float, state: DualArmState, out: ControlOutput,
           controller: DualArmController) -> None:
    """Write sample ``k`` (wall time ``t`` [s]) from the state and its command."""
    _record_state(tr, k, t, state, controller.task)
    tr.m[k] = out.m
    tr.ql_dot[k] = out.ql_dot
    tr.qf_dot[k] = out.qf_dot
    if controller.task.leader_surface is not None:
        tr.m_leader[k] = out.m_leader
    le = out.build.leader_error
    tr.leader_pos_err[k] = math.hypot(*le[:3].tolist())
    tr.leader_rot_err[k] = math.hypot(*le[3:].tolist())
    tr.sigma_min_l[k], tr.sigma_min_f[k] = out.build.sigma_min
    err = out.build.closure_error
    tr.closure_pos_err[k] = math.hypot(*err[:3].tolist())
    tr.closure_rot_err[k] = math.hypot(*err[3:].tolist())
    # K e as it entered the step: scaled with the task when it was.
    gain = float(controller.options.correction_gain or 0.0)
    if out.applied:
        gain *= out.solution.scale
    tr.feedback_pos[k] = gain * tr.closure_pos_err[k]
    tr.feedback_rot[k] = gain * tr.closure_rot_err[k]
    # The task scale, without the shortening of the sample where the path ends.
    tr.scale[k] = min(max(out.solution.scale, 0.0), 1.0) if out.applied else 0.0
    tr.status[k] = out.status.value
    tr.fallback[k] = float(out.fallback)
    sol = out.solution
    tr.objective[k] = sol.objective
    tr.eq_residual[k] = sol.eq_residual
    tr.bound_violation[k] = sol.bound_violation
    tr.kinematics_time_s[k] = out.times.kinematics
    tr.assembly_time_s[k] = out.times.assembly
    tr.solve_time_s[k] = out.times.solve
    tr.step_time_s[k] = out.times.total
    tr.support_force[k] = out.build.support_force


def record_state(tr: Trace, k: int, t: float, state: DualArmState,
                 controller: DualArmController, status: str = "error") -> None:
    """Write sample ``k`` for a state whose step raised: the state, no command.

    The rates and the path-time rate are 0 (nothing was applied); errors and solver
    fields stay NaN; the status is ``status``: ``"infeasible"`` for a step that has no
    solution (the ``"stop"`` policy), ``"error"`` for any other failure.
    """
    _record_state(tr, k, t, state, controller.task)
    tr.m[k] = 0.0
    if controller.task.leader_surface is not None:
        tr.m_leader[k] = 0.0
    tr.ql_dot[k] = 0.0
    tr.qf_dot[k] = 0.0
    tr.scale[k] = 0.0
    tr.fallback[k] = 0.0
    tr.status[k] = status
    tr.correction_l[k] = tr.correction_f[k] = 0.0


def _record_state(tr: Trace, k: int, t: float, state: DualArmState, task: DualArmTask
                  ) -> None:
    """Write the realised state of sample ``k`` (its margins come after the run)."""
    tr.t[k] = t
    tr.tau[k] = state.t
    tr.q_l[k] = state.q_l
    tr.q_f[k] = state.q_f
    tr.grasp[k] = state.sigma
    if task.leader_surface is not None:
        tr.grasp_leader[k] = state.sigma_leader


def record_margins(tr: Trace, task: DualArmTask) -> None:
    """Write every recorded sample's margins to the ranges, in one pass over the run.

    The joints' distances to their range ends [rad] and the grasps' (:func:`grasp_margins`)
    [m], from the recorded positions: the rollout calls it once, on the samples it
    recorded, instead of once per sample.
    """
    leader, follower = task.leader, task.follower
    tr.margin_qf[:] = np.minimum(tr.q_f - follower.q_min, follower.q_max - tr.q_f)
    tr.margin_ql[:] = np.minimum(tr.q_l - leader.q_min, leader.q_max - tr.q_l)
    tr.margin_grasp[:] = grasp_margins(task.surface, tr.grasp)
    if task.leader_surface is not None:
        tr.margin_grasp_leader[:] = grasp_margins(task.leader_surface, tr.grasp_leader)


def grasp_margins(surface: GraspSurface, sigma: FloatArray) -> FloatArray:
    """Signed distance of each grasp coordinate to the nearest end of its range [m].

    The range along the path, ``[sigma_min, sigma_max]``, intersected with the box of
    Eq. 3 where the surface has one (on a straight path both say the same).

    Parameters
    ----------
    surface : GraspSurface
        The path the grasp slides on.
    sigma : ndarray, shape (k,)
        Grasp coordinates [m].
    """
    sigma = np.asarray(sigma, dtype=np.float64)
    margin = np.minimum(sigma - surface.sigma_min, surface.sigma_max - sigma)
    if not (np.isfinite(surface.r_min).any() or np.isfinite(surface.r_max).any()):
        return margin
    r = surface.points(sigma)
    s = np.abs(surface.tangents(sigma))
    for i in range(3):
        moving = s[:, i] >= 1e-12  # a coordinate the path does not move along is skipped
        along = np.where(moving, s[:, i], 1.0)
        for bound, sign in ((surface.r_min[i], 1.0), (surface.r_max[i], -1.0)):
            if math.isfinite(bound):
                margin = np.where(moving, np.minimum(margin, sign * (r[:, i] - bound) / along),
                                  margin)
    return margin


def grasp_margin(surface: GraspSurface, sigma: float) -> float:
    """Signed distance of the grasp at ``sigma`` to the nearest end of its range [m].

    :func:`grasp_margins` at one grasp coordinate.
    """
    return float(grasp_margins(surface, np.array([float(sigma)]))[0])


__all__ = ["Trace", "grasp_margin", "grasp_margins", "record", "record_margins",
           "record_state"]
