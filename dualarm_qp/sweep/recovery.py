"""A run's realised limits after its start-up recovery, for the maps of a sweep.

A run may start with variables outside their ranges: the paper's Table 2 grasp (450 mm
on a 0..400 mm bar) does, and so do follower joints when its base moves. The hard-limit
solvers never move such a variable further out and the range centres pull it back, so
the run's worst range ratio over the whole run is its start, the same at every point of
a sweep that starts the same way. What tells points apart is the motion once every
variable is inside its range:

* ``recovered_at_s`` [s]: the time of the first sample with every joint of both arms
  and every grasp inside its range (0 for a run that starts inside; NaN for one that
  never gets there);
* ``worst_limit_ratio_after_recovery``: the worst realised range or speed ratio (of the
  leader, the follower and each grasp) over the samples from then on, measured as the
  whole run's (:func:`~dualarm_qp.control.realised.measure`);
* ``joint_margin_min_after_recovery_rad`` [rad]: the smallest joint margin of either arm
  from then on.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..control.realised import RANGE_TOL, measure

#: Record fields of this module, all NaN when the run never gets inside its ranges.
FIELDS = ("recovered_at_s", "worst_limit_ratio_after_recovery",
          "joint_margin_min_after_recovery_rad")


def _nanmax(values: list[float]) -> float:
    finite = [v for v in values if not math.isnan(v)]
    return max(finite) if finite else math.nan


def after_recovery(trace: Any, task: Any, grasp_speed_max: float, dt: float
                   ) -> dict[str, float]:
    """Return :data:`FIELDS` for one rollout.

    Parameters
    ----------
    trace : Trace
        The rollout's samples (:class:`~dualarm_qp.control.trace.Trace`).
    task : DualArmTask
        Its arms' joint ranges and speed limits [rad, rad/s] and grasp ranges [m].
    grasp_speed_max : float
        The sliding speed limit [m/s] (infinite: none).
    dt : float
        Sampling interval [s].
    """
    out = dict.fromkeys(FIELDS, math.nan)
    rows = len(trace.t)
    if rows == 0:
        return out
    margins = [np.asarray(trace.margin_ql, float).reshape(rows, -1),
               np.asarray(trace.margin_qf, float).reshape(rows, -1),
               np.asarray(trace.margin_grasp, float).reshape(rows, -1)]
    lead = task.leader_surface
    if lead is not None:
        margins.append(np.asarray(trace.margin_grasp_leader, float).reshape(rows, -1))
    inside = np.flatnonzero((np.hstack(margins) >= -RANGE_TOL).all(axis=1))
    if inside.size == 0:
        return out
    k0 = int(inside[0])
    parts = [(trace.q_l, task.leader.q_min, task.leader.q_max, task.leader.qd_max),
             (trace.q_f, task.follower.q_min, task.follower.q_max, task.follower.qd_max),
             (trace.grasp[:, None], [task.surface.sigma_min], [task.surface.sigma_max],
              [grasp_speed_max])]
    if lead is not None:
        parts.append((trace.grasp_leader[:, None], [lead.sigma_min], [lead.sigma_max],
                      [grasp_speed_max]))
    ratios: list[float] = []
    for x, lo, hi, v_max in parts:
        x = np.asarray(x, float)[k0:]
        report = measure(x, np.asarray(lo, float), np.asarray(hi, float),
                         np.asarray(v_max, float), dt, [str(j) for j in range(x.shape[1])],
                         speed_rule=False)
        ratios += [report.range_ratio, report.speed_ratio]
    out["recovered_at_s"] = float(trace.t[k0] - trace.t[0])
    out["worst_limit_ratio_after_recovery"] = _nanmax(ratios)
    joints = np.hstack(margins[:2])[k0:]
    out["joint_margin_min_after_recovery_rad"] = float(np.nanmin(joints)) \
        if np.isfinite(joints).any() else math.nan
    return out
