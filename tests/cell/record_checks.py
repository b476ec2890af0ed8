"""Checks of a drive's folder that read only its files: trajectory.csv, summary.json and
the experiment file (for the limits, the arms' kinematics and the path).

Speeds, accelerations and jerks are divided differences of the recorded joints over
the robots' own clock (``robot_t``): speeds between two samples, accelerations between
two speeds (their midpoints' distance), jerks between two accelerations; from rest.
"""

from __future__ import annotations

import csv
import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin
import yaml

from dualarm_qp.experiments.config import load_config
from dualarm_qp.experiments.setup import build_experiment

#: Relative slack on a limit: rounding of the CSV's numbers (17 digits) and of the
#: differences.
RTOL = 1e-6


@dataclass
class Record:
    """A drive's folder as read from its files."""

    summary: dict
    header: list[str]
    rows: list[dict[str, str]]

    def col(self, name: str, rows: slice | None = None) -> np.ndarray:
        sel = self.rows if rows is None else self.rows[rows]
        return np.array([float(r[name]) for r in sel])

    def cols(self, names: list[str], rows: slice | None = None) -> np.ndarray:
        return np.column_stack([self.col(n, rows) for n in names])

    @property
    def control(self) -> slice:
        """The control samples (the stop's rows, status ``stopping``, come after)."""
        return slice(0, sum(r["status"] != "stopping" for r in self.rows))


def read_record(out: Path) -> Record:
    """Read ``out`` and check that it is whole: every row complete, as many as listed."""
    names = {p.name for p in out.iterdir()}
    assert not [n for n in names if n.startswith(".")], f"temporary files: {names}"
    summary = json.loads((out / "summary.json").read_text())
    assert set(summary["outputs"]) == names - {"summary.json"}, (summary["outputs"], names)
    with (out / "trajectory.csv").open(newline="") as fh:
        raw = list(csv.reader(fh))
    header, body = raw[0], raw[1:]
    assert len(body) == summary["samples"]
    status = header.index("status")
    for row in body:
        assert len(row) == len(header)
        for j, value in enumerate(row):
            assert value != ""
            if j != status:
                float(value)
    rows = [dict(zip(header, r, strict=True)) for r in body]
    statuses = [r["status"] for r in rows]
    first_stop = statuses.index("stopping") if "stopping" in statuses else len(rows)
    assert all(s == "stopping" for s in statuses[first_stop:])
    return Record(summary, header, rows)


def file_limits(config: Path) -> dict[str, np.ndarray]:
    """Both arms' speed, acceleration and jerk limits from the file [rad/s^n]."""
    data = yaml.safe_load(config.read_text())
    assert data["units"]["angle"] == "deg"
    return {key: np.radians(np.r_[data["leader"][key], data["follower"][key]])
            for key in ("qd_max", "qdd_max", "qddd_max")}


def differences(q: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Speeds, accelerations and jerks of ``q`` sampled at ``t``, from rest."""
    h = np.diff(t)
    v = np.diff(q, axis=0) / h[:, None]
    mid = np.r_[h[0], 0.5 * (t[2:] - t[:-2])]
    a = np.diff(np.vstack([np.zeros(q.shape[1]), v]), axis=0) / mid[:, None]
    back = np.r_[h[0], h[:-1]]
    j = np.diff(np.vstack([np.zeros(q.shape[1]), a]), axis=0) / back[:, None]
    return v, a, j


def joint_names() -> list[str]:
    return [f"ql{j}" for j in range(1, 8)] + [f"qf{j}" for j in range(1, 8)]


def sent_names() -> list[str]:
    return [f"ql_sent{j}" for j in range(1, 8)] + [f"qf_sent{j}" for j in range(1, 8)]


def check_motion(rec: Record, config: Path, rows: slice | None = None) -> dict[str, float]:
    """The recorded joints keep every range, speed, acceleration and jerk limit.

    Returns the worst ratio of each (at most 1).
    """
    lim = file_limits(config)
    exp = build_experiment(load_config(config), str(config))
    q = rec.cols(joint_names(), rows)
    t = rec.col("robot_t", rows)
    assert np.all(np.diff(t) > 0), "the robots' clock must advance every sample"
    lo = np.r_[exp.task.leader.q_min, exp.task.follower.q_min]
    hi = np.r_[exp.task.leader.q_max, exp.task.follower.q_max]
    assert np.all(q >= lo) and np.all(q <= hi)
    v, a, j = differences(q, t)
    ratios = {"speed": float(np.max(np.abs(v) / lim["qd_max"])),
              "acceleration": float(np.max(np.abs(a) / lim["qdd_max"])),
              "jerk": float(np.max(np.abs(j) / lim["qddd_max"]))}
    for what, ratio in ratios.items():
        assert ratio <= 1 + RTOL, f"the recorded {what} reached {ratio:.4f} of its limit"
    return ratios


def check_sent(rec: Record, config: Path) -> None:
    """The commands sent (the stop's too), from rest, keep the speed, acceleration and
    jerk limits on the controller's samples, and the last one is at rest."""
    lim = file_limits(config)
    dt = float(yaml.safe_load(config.read_text())["controller"]["dt"])
    sent = np.vstack([np.zeros((2, 14)), rec.cols(sent_names())])
    assert np.all(np.abs(sent) <= lim["qd_max"] * (1 + RTOL))
    acc = np.abs(np.diff(sent, axis=0)) / dt
    assert np.all(acc <= lim["qdd_max"] * (1 + RTOL)), np.max(acc / lim["qdd_max"])
    jerk = np.abs(np.diff(sent, n=2, axis=0)) / dt**2
    assert np.all(jerk <= lim["qddd_max"] * (1 + RTOL)), np.max(jerk / lim["qddd_max"])
    assert not np.any(sent[-1]), "the last command sent is not at rest"


def check_task(rec: Record, config: Path) -> tuple[float, float]:
    """The object follows D(path_t) and the follower's hand stays on its grasp line,
    within the file's tolerances, on the control samples.

    The object's pose is the leader's hand times ``H1``; the grasp coordinate is the
    projection of the follower's hand on the line. Returns the worst position errors [m].
    """
    cfg = load_config(config)
    exp = build_experiment(cfg, str(config))
    task = exp.task
    closure_tol, tracking_tol = exp.limits.closure, exp.limits.tracking
    data = yaml.safe_load(config.read_text())["controller"]
    assert closure_tol[0] == data["closure_tolerance"][0] * 1e-3
    assert tracking_tol[0] == data["tracking_tolerance"][0] * 1e-3
    ql, qf = rec.cols(joint_names()[:7], rec.control), rec.cols(joint_names()[7:], rec.control)
    path_t = rec.col("path_t", rec.control)
    worst_closure = worst_tracking = 0.0
    for k in range(len(path_t)):
        T_obj = task.object_pose(ql[k])
        D = task.trajectory.pose(path_t[k])
        pos = float(np.linalg.norm(T_obj[:3, 3] - D[:3, 3]))
        rot = float(np.linalg.norm(pin.log3(T_obj[:3, :3] @ D[:3, :3].T)))
        assert pos <= tracking_tol[0] and rot <= tracking_tol[1], (k, pos, rot)
        T_f = task.follower.fk(qf[k])
        p_obj = T_obj[:3, :3].T @ (T_f[:3, 3] - T_obj[:3, 3])
        target = T_obj @ task.surface.pose(float(task.surface.sigma_of(p_obj)))
        c_pos = float(np.linalg.norm(target[:3, 3] - T_f[:3, 3]))
        c_rot = float(np.linalg.norm(pin.log3(target[:3, :3] @ T_f[:3, :3].T)))
        assert c_pos <= closure_tol[0] and c_rot <= closure_tol[1], (k, c_pos, c_rot)
        worst_closure, worst_tracking = max(worst_closure, c_pos), max(worst_tracking, pos)
    assert math.isclose(path_t[-1], exp.duration) or rec.summary["status"] != "completed"
    return worst_closure, worst_tracking
