"""The realised checks: the recorded motion against the limits, as failures.

After the loop, the recorded positions are measured against the ranges, speeds and
accelerations of both arms and of the grasps (:func:`.realised.measure`), and their
clearance and joint torques against the scene and the torque limits; a breach becomes
the :class:`~.failure.Failure` of the run (:mod:`.verdict` decides when it counts).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from ..collision.clearance import ClearanceReport
from .controller import DualArmController
from .failure import Failure
from .realised import LimitReport, measure
from .torques import TorqueReport
from .trace import Trace

FloatArray = NDArray[np.float64]


def realised_reports(controller: DualArmController, trace: Trace, dt: float,
              v_start: FloatArray | None = None) -> dict[str, LimitReport]:
    """Measure the realised motion of both arms and of the grasp against their limits.

    ``v_start`` holds the rates the run started with (decision order; default zero).
    Speeds and accelerations are measured against the arms' limits always; they decide
    completion only when the step imposed them (``velocity_limits``,
    ``acceleration_limits``).
    """
    task, opts = controller.task, controller.options
    lay = controller.layout
    start = lay.split(np.zeros(lay.n) if v_start is None else v_start)
    reports = {}
    speed_rule = opts.velocity_limits
    accel_rule = opts.acceleration_limits
    for role, arm, q, v0 in (("leader", task.leader, trace.q_l, start[0]),
                             ("follower", task.follower, trace.q_f, start[1])):
        prefix = "ql" if role == "leader" else "qf"
        reports[role] = measure(q, arm.q_min, arm.q_max, arm.qd_max, dt,
                                [f"{prefix}{j + 1}" for j in range(arm.n)],
                                speed_rule=speed_rule, a_max=arm.qdd_max, v_start=v0,
                                acceleration_rule=accel_rule, j_max=arm.qddd_max,
                                jerk_rule=opts.jerk_limits)
    surface = task.surface
    a_grasp = np.array([opts.grasp_acc_max])
    reports["grasp"] = measure(trace.grasp[:, None], np.array([surface.sigma_min]),
                               np.array([surface.sigma_max]),
                               np.array([opts.grasp_speed_max]), dt, ["grasp"],
                               speed_rule=speed_rule, a_max=a_grasp,
                               v_start=np.array([start[2]]), acceleration_rule=accel_rule,
                               j_max=np.array([opts.grasp_jerk_max]), jerk_rule=opts.jerk_limits)
    lead = task.leader_surface
    if lead is not None:
        reports["grasp_leader"] = measure(
            trace.grasp_leader[:, None], np.array([lead.sigma_min]), np.array([lead.sigma_max]),
            np.array([opts.grasp_speed_max]), dt, ["grasp_leader"], speed_rule=speed_rule,
            a_max=a_grasp, v_start=np.array([start[3]]), acceleration_rule=accel_rule)
    return reports


def realised_failure(realised: dict[str, LimitReport], trace: Trace, dt: float
                      ) -> Failure | None:
    """Return the earliest realised-limit breach of a hard-limit run, as a failure."""
    breaches = [r.breach for r in realised.values() if r.breach is not None]
    if not breaches:
        return None
    b = min(breaches, key=lambda b: b.sample)
    t = float(trace.t[b.sample])
    return Failure(b.criterion, b.sample, t, b.amount, b.limit,
                   f"step {b.sample} at t = {t:.4f} s: realised motion broke a limit: "
                   f"{b.describe(dt)}")


def clearance_failure(report: ClearanceReport, trace: Trace) -> Failure:
    """Return the failure of a run whose recorded clearance fell below ``d_s - allowance``."""
    k = report.breach_sample
    t = float(trace.t[k])
    d = float(min(trace.clearance_arm_arm[k], trace.clearance_arm_object[k],
                  trace.clearance_obstacles[k], trace.clearance_self[k]))
    limit = report.safety_distance - report.allowance
    return Failure("collision", k, t, d, limit,
                   f"step {k} at t = {t:.4f} s: the recorded motion brought "
                   f"{trace.clearance_pair[k]} to {d * 1e3:.2f} mm, below the safety "
                   f"distance {report.safety_distance * 1e3:.1f} mm less the allowance "
                   f"{report.allowance * 1e3:.1f} mm")


def torque_failure(report: TorqueReport, trace: Trace) -> Failure:
    """Return the failure of a run whose recorded torque went beyond its limit and allowance.

    A run whose grasps could not hold the load at some sample (no torque there) fails at
    the first such sample.
    """
    if report.breach_sample < 0 or 0 <= report.first_unbalanced < report.breach_sample:
        k = report.first_unbalanced
        t = float(trace.t[k])
        return Failure("torque", k, t, math.nan, math.nan,
                       f"step {k} at t = {t:.4f} s: the grasps cannot hold the load there, "
                       f"so the joint torques are not known ({report.unbalanced} such "
                       "samples)")
    k = report.breach_sample
    t = float(trace.t[k])
    tau = np.r_[trace.tau_leader[k], trace.tau_follower[k]]
    n_l = trace.tau_leader.shape[1]
    names = [f"ql{i + 1}" for i in range(n_l)] + [f"qf{i + 1}"
                                                   for i in range(trace.tau_follower.shape[1])]
    j = names.index(report.breach_joint)
    limit = report.breach_limit
    return Failure("torque", k, t, float(tau[j]), limit,
                   f"step {k} at t = {t:.4f} s: the recorded motion needs "
                   f"{tau[j]:.4g} N m at joint {report.breach_joint}, beyond its limit of "
                   f"{limit:.4g} N m and the allowance of {100 * report.allowance_rtol:g}%")


__all__ = ["clearance_failure", "realised_failure", "realised_reports", "torque_failure"]
