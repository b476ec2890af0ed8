"""Check the RECORDED motion in ``trajectory.csv`` against the limits, independently of
``summary.json`` and of the library's own checks.

The limits and geometry (joint ranges, speed limits, D(t), H1, the grasp surface, the arm
bases) are inputs read from the built experiment; the realised joints and grasp come from
the CSV only, and forward kinematics comes from :mod:`oracle`, not from the library.
Every check returns a list of human-readable violations (empty: the rule holds).
"""

from __future__ import annotations

import csv
import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from clearance_check import check_clearance
from oracle import inv_pose, is_puma, puma_fk

SPEED_RTOL = 1e-6      # |dx|/dt <= v_max * (1 + SPEED_RTOL)
ACCEL_RTOL = 1e-6      # |dv|/dt <= a_max * (1 + ACCEL_RTOL), v from consecutive rows
RANGE_TOL = 1e-9       # the distance outside [lo, hi] may not grow by more than this
PATH_TOL = 1e-9        # last path_t == t0 + duration
POSITION_TOL = 1e-3    # leader tracking and grasp closure, metres

LEADER = [f"ql{i}" for i in range(1, 7)]     # the PUMA 560's columns
FOLLOWER = [f"qf{i}" for i in range(1, 7)]
FAILURE_CRITERIA = frozenset({"unreachable", "solver", "closure", "tracking", "singularity",
                              "stalled", "path_incomplete", "range", "speed", "acceleration",
                              "path_collision", "collision"})


def read_trajectory(path: str | Path) -> dict[str, np.ndarray]:
    """Columns of the CSV by header name: float arrays, or str arrays for text columns."""
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    header, body = rows[0], rows[1:]
    out: dict[str, np.ndarray] = {}
    for j, name in enumerate(header):
        col = [r[j] for r in body]
        try:
            out[name] = np.array([float(v) for v in col], dtype=float)
        except ValueError:
            out[name] = np.array(col, dtype=object)
    return out


def write_trajectory(path: str | Path, traj: dict[str, np.ndarray]) -> None:
    """Write ``traj`` back as a CSV (full float precision), for doctored copies."""
    names = list(traj)
    n = len(traj[names[0]])
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(names)
        for k in range(n):
            w.writerow([repr(float(traj[c][k])) if traj[c].dtype != object else traj[c][k]
                        for c in names])


@dataclass
class Limits:
    """The limits a hard-limit run must keep, in SI units."""

    dt: float
    t_end: float
    speed_limits: bool
    bounds: dict[str, tuple[float, float]]   # column -> (lo, hi)
    speeds: dict[str, float]                 # column -> v_max
    acceleration_limits: bool = False
    accelerations: dict[str, float] | None = None   # column -> a_max
    start_rates: dict[str, float] | None = None     # column -> rate before row 0


def joint_columns(traj: dict[str, np.ndarray], prefix: str) -> list[str]:
    """The CSV's joint columns ``<prefix>1``, ``<prefix>2``, ... in order (any joint count)."""
    found = sorted((int(m.group(1)), c) for c in traj
                   if (m := re.fullmatch(rf"{prefix}(\d+)", c)))
    return [c for _, c in found]


def limits_of(exp: Any) -> Limits:
    """Every joint's range and speed limit (any joint count), the grasp's, and the
    leader's grasp's when it slides (column ``grasp_leader``)."""
    task, opts = exp.task, exp.options
    bounds: dict[str, tuple[float, float]] = {}
    speeds: dict[str, float] = {}
    accelerations: dict[str, float] = {}
    for prefix, arm in (("ql", task.leader), ("qf", task.follower)):
        for i in range(arm.n):
            bounds[f"{prefix}{i + 1}"] = (float(arm.q_min[i]), float(arm.q_max[i]))
            speeds[f"{prefix}{i + 1}"] = float(arm.qd_max[i])
            accelerations[f"{prefix}{i + 1}"] = float(arm.qdd_max[i])
    surfaces = [("grasp", task.surface)]
    if task.leader_surface is not None:
        surfaces.append(("grasp_leader", task.leader_surface))
    for c, surface in surfaces:
        bounds[c] = (float(surface.sigma_min), float(surface.sigma_max))
        speeds[c] = float(opts.grasp_speed_max)
        accelerations[c] = float(opts.grasp_acc_max)
    # The rates before the first row: zero from rest (the config's default), otherwise
    # the experiment's own start (read from the experiment, not from the run's outputs).
    start = np.zeros(len(accelerations))
    rates = exp.start_rates()
    if rates is not None:
        start = np.asarray(rates, dtype=float)
    return Limits(dt=float(opts.dt), t_end=float(exp.initial.t) + float(exp.duration),
                  speed_limits=bool(opts.velocity_limits), bounds=bounds, speeds=speeds,
                  acceleration_limits=bool(opts.acceleration_limits),
                  accelerations=accelerations,
                  start_rates=dict(zip(accelerations, start.tolist(), strict=True)))


def check_valid(traj: dict[str, np.ndarray]) -> list[str]:
    """Every row finite in t, path_t, the joints and the grasp(s); at least one row.

    The joint columns are read from the header (``ql1..``, ``qf1..``: any joint count,
    at least one each).
    """
    out = []
    leader, follower = joint_columns(traj, "ql"), joint_columns(traj, "qf")
    for prefix, cols in (("ql", leader), ("qf", follower)):
        if not cols:
            out.append(f"missing column {prefix}1")
    extra = ["grasp_leader"] if "grasp_leader" in traj else []
    for c in ["t", "path_t", *leader, *follower, "grasp", *extra]:
        if c not in traj:
            out.append(f"missing column {c}")
            continue
        col = traj[c]
        if col.dtype == object:
            out.append(f"column {c} is not numeric")
        elif len(col) == 0:
            out.append("no rows")
        elif not np.isfinite(col).all():
            out.append(f"column {c}: non-finite at rows {np.flatnonzero(~np.isfinite(col))[:5]}")
    return out


def check_speeds(traj: dict[str, np.ndarray], lim: Limits) -> list[str]:
    """|x[k+1] - x[k]| / dt <= v_max (1 + 1e-6) for every joint and the grasp."""
    if not lim.speed_limits:
        return []
    out = []
    for c, vmax in lim.speeds.items():
        if not math.isfinite(vmax):
            continue
        v = np.abs(np.diff(traj[c])) / lim.dt
        bad = np.flatnonzero(v > vmax * (1 + SPEED_RTOL))
        if bad.size:
            k = int(bad[np.argmax(v[bad])])
            out.append(f"speed {c}: {bad.size} steps over; worst rows {k}->{k + 1} "
                       f"(t={traj['t'][k]:.6g} s): {v[k]:.9g} > {vmax:.9g} "
                       f"(ratio {v[k] / vmax:.9g})")
    return out


def check_accelerations(traj: dict[str, np.ndarray], lim: Limits) -> list[str]:
    """|v[k] - v[k-1]| / dt <= a_max (1 + 1e-6), with v[k] = (x[k+1] - x[k]) / dt and
    v[-1] the rates the run started with (zero from rest): the first sample from rest
    counts too."""
    if not lim.acceleration_limits or lim.accelerations is None:
        return []
    out = []
    for c, amax in lim.accelerations.items():
        if not math.isfinite(amax):
            continue
        v0 = (lim.start_rates or {}).get(c, 0.0)
        v = np.concatenate([[v0], np.diff(traj[c]) / lim.dt])
        a = np.abs(np.diff(v)) / lim.dt
        bad = np.flatnonzero(a > amax * (1 + ACCEL_RTOL))
        if bad.size:
            k = int(bad[np.argmax(a[bad])])
            out.append(f"acceleration {c}: {bad.size} samples over; worst at row {k} "
                       f"(t={traj['t'][k]:.6g} s): {a[k]:.9g} > {amax:.9g} "
                       f"(ratio {a[k] / amax:.9g})")
    return out


def outside(x: np.ndarray, lo: float, hi: float) -> np.ndarray:
    return np.maximum(np.maximum(lo - x, x - hi), 0.0)


def check_ranges(traj: dict[str, np.ndarray], lim: Limits) -> list[str]:
    """The distance outside [lo, hi] never exceeds its smallest earlier value (+1e-9)."""
    out = []
    for c, (lo, hi) in lim.bounds.items():
        d = outside(traj[c], lo, hi)
        growth = d[1:] - np.minimum.accumulate(d)[:-1]
        bad = np.flatnonzero(growth > RANGE_TOL)
        if bad.size:
            k = int(bad[np.argmax(growth[bad])])
            out.append(f"range {c} [{lo:.9g}, {hi:.9g}]: {bad.size} steps moving out; worst "
                       f"rows {k}->{k + 1} (t={traj['t'][k]:.6g} s): value "
                       f"{traj[c][k]:.12g} -> {traj[c][k + 1]:.12g}, outside "
                       f"{d[k]:.3e} -> {d[k + 1]:.3e}")
    return out


def check_path_complete(traj: dict[str, np.ndarray], lim: Limits) -> list[str]:
    last = float(traj["path_t"][-1])
    if abs(last - lim.t_end) > PATH_TOL:
        return [f"path incomplete: last path_t {last!r} != t0 + duration {lim.t_end!r} "
                f"(diff {last - lim.t_end:.3e})"]
    return []


def _q(traj: dict[str, np.ndarray], cols: list[str], k: int) -> np.ndarray:
    return np.array([traj[c][k] for c in cols])


def check_geometry(traj: dict[str, np.ndarray], exp: Any) -> list[str]:
    """Leader tracking and grasp closure (positions, 1 mm) with the oracle's kinematics."""
    task = exp.task
    out = []
    for arm in (task.leader, task.follower):
        if not is_puma(arm):
            return [f"{arm.name}: not the PUMA 560 table the oracle knows"]
    H1 = np.asarray(task.H1, dtype=float)
    H1_inv = inv_pose(H1)
    track = np.empty(len(traj["t"]))
    close = np.empty(len(traj["t"]))
    for k in range(len(traj["t"])):
        T_l = puma_fk(_q(traj, LEADER, k), task.leader.base, task.leader.tool)
        target = np.asarray(task.trajectory.pose(float(traj["path_t"][k]))) @ H1_inv
        track[k] = np.linalg.norm(T_l[:3, 3] - target[:3, 3])
        T_f = puma_fk(_q(traj, FOLLOWER, k), task.follower.base, task.follower.tool)
        grasp = T_l @ H1 @ np.asarray(task.surface.pose(float(traj["grasp"][k])))
        close[k] = np.linalg.norm(T_f[:3, 3] - grasp[:3, 3])
    for name, err in (("leader tracking", track), ("grasp closure", close)):
        bad = np.flatnonzero(err > POSITION_TOL)
        if bad.size:
            k = int(np.argmax(err))
            out.append(f"{name}: {bad.size} rows over 1 mm; worst row {k} "
                       f"(t={traj['t'][k]:.6g} s, path_t={traj['path_t'][k]:.6g}): "
                       f"{err[k] * 1e3:.6g} mm")
    return out


def check_completed_run(traj: dict[str, np.ndarray], exp: Any) -> list[str]:
    """Every rule a completed hard-limit run must keep (with a collision scene, its
    recorded clearance too: :func:`clearance_check.check_clearance`)."""
    bad = check_valid(traj)
    if bad:
        return bad
    lim = limits_of(exp)
    return (check_speeds(traj, lim) + check_accelerations(traj, lim)
            + check_ranges(traj, lim) + check_path_complete(traj, lim)
            + check_geometry(traj, exp) + check_clearance(traj, exp))


def worst_shares(traj: dict[str, np.ndarray], exp: Any) -> dict[str, float]:
    """For reports: the worst speed share, range growth and position errors of a record."""
    lim = limits_of(exp)
    out: dict[str, float] = {}
    if lim.speed_limits and len(traj["t"]) > 1:
        out["speed_share"] = max(float(np.max(np.abs(np.diff(traj[c]))) / lim.dt / v)
                                 for c, v in lim.speeds.items() if math.isfinite(v))
    if len(traj["t"]) > 1:
        out["range_growth"] = max(float(np.max(np.diff(outside(traj[c], lo, hi))))
                                  for c, (lo, hi) in lim.bounds.items())
    return out
