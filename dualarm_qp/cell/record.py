"""The cell's own record: its columns of ``trajectory.csv``, its realised limits, its stop.

Columns added after those of ``run`` (which keep their names and order):

* ``robot_t`` [s]: the cell's clock of the state the row acted on (a simulator's time,
  the ROS clock, the robot's own clock); ``t`` stays the nominal sample time
  ``k dt``;
* ``state_age`` [s]: how old that state was on the cell's clock when it was read (the
  watchdog's measure);
* ``ql_sent1 ..``, ``qf_sent1 ..`` [rad/s]: the rates sent to the robots (after the
  clamp; the stop ramp's on ``stopping`` rows; in a dry run: what would have been sent),
  beside ``ql_dot*``, ``qf_dot*``, the rates the controller computed;
* ``clamped`` [rad/s]: the largest change the clamp made to the computed rates;
* ``grasp_measured`` [m]: the grasp coordinate a simulator measured (NaN on hardware;
  ``grasp`` is the estimate the controller used);
* ``state_late`` [s]: how far past ``robot_t`` the later arm's state was stamped (two
  arms' states read at the same sample may be a tick apart; that arm's joints are
  brought back to ``robot_t`` with its measured rates);
* ``measured_offset`` [rad] (dry run only): the largest distance between the measured
  joints and the model's state the controller acted on.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..control.realised import LimitReport, measure
from ..control.trace import Trace
from ..step.options import StepOptions
from ..task.scene import DualArmTask
from .safety import CommandLimits

FloatArray = NDArray[np.float64]


def cell_columns(robot_t: Sequence[float], age: Sequence[float], sent: Sequence[FloatArray],
                 computed: Sequence[FloatArray], sigma_measured: Sequence[float], n_l: int,
                 *, late: Sequence[float] | None = None,
                 offset: Sequence[float] | None = None) -> dict[str, Any]:
    """Return the cell's columns of ``trajectory.csv`` (see the module), in order."""
    rows = len(robot_t)
    width = sent[0].size if rows else n_l
    s = np.asarray(sent, dtype=np.float64).reshape(rows, width)
    c = np.asarray(computed, dtype=np.float64).reshape(rows, width)
    cols: dict[str, Any] = {"robot_t": np.asarray(robot_t, dtype=np.float64),
                            "state_age": np.asarray(age, dtype=np.float64)}
    for j in range(n_l):
        cols[f"ql_sent{j + 1}"] = s[:, j]
    for j in range(width - n_l):
        cols[f"qf_sent{j + 1}"] = s[:, n_l + j]
    cols["clamped"] = np.max(np.abs(s - c), axis=1, initial=0.0)
    cols["grasp_measured"] = np.asarray(sigma_measured, dtype=np.float64)
    cols["state_late"] = (np.zeros(rows) if late is None
                          else np.asarray(late, dtype=np.float64))
    if offset is not None:
        cols["measured_offset"] = np.asarray(offset, dtype=np.float64)
    return cols


def cell_realised(task: DualArmTask, opts: StepOptions, trace: Trace,
                  times: FloatArray) -> dict[str, LimitReport]:
    """Measure the motion of the control samples against every limit of both arms.

    ``task`` holds the limits the motion is judged by (the file's: a cell's controller
    commands within ``1 - headroom`` of them), ``opts`` says which the step imposed;
    ``times`` are the samples' times on the cell's clock (``robot_t``) [s]: each
    difference divides by its own interval (a late tick is measured as late), and a
    state read again (the same stamp) counts once.

    As a run's realised check (:mod:`dualarm_qp.control.realised`), from rest: ranges,
    speeds, accelerations (second differences) and, with jerk limits, jerks (third
    differences) of the recorded joints, each a breach only when the step imposes it.
    The grasp (an estimate on hardware) is measured against its range and speed.
    """
    # A state read again (the same stamp: a driver that fell behind) is one sample.
    keep = np.flatnonzero(np.r_[True, np.diff(times) > 0.0]) if len(times) else np.arange(0)
    t = np.asarray(times, dtype=np.float64)[keep]
    reports = {}
    for role, arm, q in (("leader", task.leader, trace.q_l),
                         ("follower", task.follower, trace.q_f)):
        prefix = "ql" if role == "leader" else "qf"
        reports[role] = measure(q[keep], arm.q_min, arm.q_max, arm.qd_max, t,
                                [f"{prefix}{j + 1}" for j in range(arm.n)],
                                speed_rule=opts.velocity_limits, a_max=arm.qdd_max,
                                acceleration_rule=opts.acceleration_limits,
                                j_max=arm.qddd_max, jerk_rule=opts.jerk_limits)
    surface = task.surface
    reports["grasp"] = measure(trace.grasp[keep, None], np.array([surface.sigma_min]),
                               np.array([surface.sigma_max]), np.array([opts.grasp_speed_max]),
                               t, ["grasp"], speed_rule=False)
    return {k: _rows_of(r, keep) for k, r in reports.items()}


def _rows_of(report: LimitReport, keep: NDArray[np.intp]) -> LimitReport:
    """``report`` with its breach's sample counted in the record's rows."""
    b = report.breach
    if b is None:
        return report
    return dataclasses.replace(report, breach=dataclasses.replace(b, sample=int(keep[b.sample])))


def stop_summary(limits: CommandLimits, sent: Sequence[FloatArray], first: int,
                 reason: str) -> dict[str, Any]:
    """Return the stop's part of the summary: why, how long, and its commands against the limits.

    ``sent`` holds every row's command; the stop's are those from row ``first`` on. The
    accelerations and jerks are the differences over ``dt`` of the stop's commands and
    the two before them (zero before the first row: the run starts at rest); a ratio of
    at most 1 keeps the limit (the commanded one: the file's times ``1 - headroom``).
    """
    dt = limits.dt
    s = np.asarray(sent, dtype=np.float64).reshape(len(sent), limits.n)
    samples = max(len(s) - first, 0)
    out: dict[str, Any] = {"reason": reason, "samples": int(samples),
                           "duration_s": float(samples * dt),
                           "at_rest": bool(len(s) == 0 or not np.any(s[-1])),
                           "acceleration_ratio_max": math.nan, "jerk_ratio_max": math.nan}
    if samples:
        seq = np.vstack([np.zeros((2, limits.n)), s])[first:]  # two before the stop's
        acc = np.abs(np.diff(seq, axis=0)) / dt
        jerk = np.abs(np.diff(seq, n=2, axis=0)) / dt**2
        with np.errstate(invalid="ignore", divide="ignore"):
            out["acceleration_ratio_max"] = float(np.max(np.where(
                np.isfinite(limits.a_max), acc[1:] / limits.a_max, 0.0), initial=0.0))
            out["jerk_ratio_max"] = float(np.max(np.where(
                np.isfinite(limits.j_max), jerk / limits.j_max, 0.0), initial=0.0))
    return out


__all__ = ["cell_columns", "cell_realised", "stop_summary"]
