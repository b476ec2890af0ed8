"""Writing run outputs: the CSV trace and the JSON summary, each file atomically.

An output folder holds the files of one run (or one reproduction); a command *owns*
the files it writes there (and the temporary files it writes them through), and
replaces or removes only those: any other file in the folder is left alone.
"""

from __future__ import annotations

import csv
import io
import re
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np

from .._io import atomic_open, atomic_write_with, write_json
from ..control.trace import Trace
from ..errors import InvalidInputError

__all__ = ["atomic_open", "atomic_write_with", "check_unused_folder", "csv_columns",
           "owned_entries", "remove_owned", "trace_columns", "write_json", "write_trace_csv"]


def _temp_pattern(names: Iterable[str]) -> re.Pattern[str]:
    """Names of the temporary files :mod:`dualarm_qp._io` writes ``names`` through."""
    alts = "|".join(re.escape(n) for n in names)
    return re.compile(rf"\.({alts})\.[A-Za-z0-9_]{{8}}\.[A-Za-z0-9]+")


def owned_entries(folder: Path, names: Iterable[str]) -> list[Path]:
    """Files in ``folder`` that a command owns: ``names`` and their temporary files.

    Parameters
    ----------
    folder : Path
        The output folder (missing: nothing is owned).
    names : iterable of str
        The file names the command writes there.

    Returns
    -------
    list of Path
        Sorted; only regular files (or links), never folders.
    """
    names = tuple(names)
    if not folder.is_dir() or not names:
        return []
    temp = _temp_pattern(names)
    return sorted(p for p in folder.iterdir()
                  if (p.name in names or temp.fullmatch(p.name))
                  and (p.is_symlink() or p.is_file()))


def remove_owned(folder: Path, names: Iterable[str]) -> list[str]:
    """Remove the files of ``names`` (and their temporary files) from ``folder``.

    Returns
    -------
    list of str
        The names removed; nothing else in the folder is touched.
    """
    removed = []
    for path in owned_entries(folder, names):
        path.unlink(missing_ok=True)
        removed.append(path.name)
    return removed


def check_unused_folder(folder: Path, *, force: bool, what: str = "a run",
                        names: Iterable[str] = ()) -> None:
    """Refuse an output folder that already holds files, unless ``force``.

    Parameters
    ----------
    folder : Path
        The output folder; missing or empty is fine.
    force : bool
        Accept a folder that holds files: the command then replaces only the files
        it owns (:func:`owned_entries`) and keeps the others.
    what : str
        What writes there, for the message.
    names : iterable of str
        The file names the command writes there: one that exists as something other than
        a file (a folder) cannot be replaced, even with ``force``.

    Raises
    ------
    InvalidInputError
        The folder holds files and ``force`` is False, or an owned name is not a file.
    """
    if not folder.is_dir():
        return
    for name in names:
        entry = folder / name
        if entry.exists() and not (entry.is_file() or entry.is_symlink()):
            raise InvalidInputError(f"{entry} is in the way: {what} writes a file there "
                                    "and will not replace a folder; move it away")
    if force:
        return
    entries = sorted(p.name + ("/" if p.is_dir() else "") for p in folder.iterdir())
    if entries:
        shown = ", ".join(entries[:5]) + (f" and {len(entries) - 5} more"
                                          if len(entries) > 5 else "")
        raise InvalidInputError(
            f"the output folder {folder} is not empty ({shown}); choose another --out, "
            f"or pass --force to replace the files {what} writes there (other files are "
            "kept)")


def trace_columns(trace: Trace) -> dict[str, Any]:
    """Return the CSV columns of a trace, in order, SI units.

    ``t, path_t, ql*, qf*, grasp`` are the realised motion; ``m, ql_dot*, qf_dot*`` the
    commanded (applied) rates of the row's step; ``closure_*_err_pre`` and
    ``correction_*`` the closure error before, and the size of, any position-level
    correction; ``feedback_*`` the closure feedback in the step; ``support_force`` [N]
    the push of a supporting follower (only when it supports: Case 2). With a collision
    scene, ``clearance_arm_arm``, ``clearance_arm_object``, ``clearance_obstacles`` (and
    ``clearance_self`` for arms with self-collision pairs) are the smallest signed
    distance [m] of each group of pairs (``inf``: a group without pairs) and
    ``clearance_pair`` the nearest pair. With a load (``object.mass``),
    ``f_leader_fx .. f_leader_mz`` and ``f_follower_fx .. f_follower_mz`` are the
    wrench each hand applies to the object [N, N m] (world frame, moment about the
    hand's grasp point; NaN where the grasps cannot hold it). With a load or torque
    limits, ``tau_leader_1 ..`` and ``tau_follower_1 ..`` are each joint's quasi-static
    torque [N m] (the arm's weight and its hand's share of the load). Against a plant
    that measures the hands' wrenches, what it measured (:func:`_measured_columns`).
    ``scale`` is the task scale (:class:`~dualarm_qp.control.trace.Trace`): the share
    of the path rate asked for that the limits allowed, 1 when not slowed, the last row
    included.
    """
    cols: dict[str, Any] = {"t": trace.t, "path_t": trace.tau}
    for j in range(trace.q_l.shape[1]):
        cols[f"ql{j + 1}"] = trace.q_l[:, j]
    for j in range(trace.q_f.shape[1]):
        cols[f"qf{j + 1}"] = trace.q_f[:, j]
    cols["grasp"] = trace.grasp
    cols["m"] = trace.m
    for j in range(trace.ql_dot.shape[1]):
        cols[f"ql_dot{j + 1}"] = trace.ql_dot[:, j]
    for j in range(trace.qf_dot.shape[1]):
        cols[f"qf_dot{j + 1}"] = trace.qf_dot[:, j]
    cols["closure_pos_err"] = trace.closure_pos_err
    cols["closure_rot_err"] = trace.closure_rot_err
    cols["leader_pos_err"] = trace.leader_pos_err
    cols["leader_rot_err"] = trace.leader_rot_err
    for j in range(trace.margin_qf.shape[1]):
        cols[f"margin_qf{j + 1}"] = trace.margin_qf[:, j]
    cols["margin_ql_min"] = np.min(trace.margin_ql, axis=1) if len(trace) else trace.t
    cols["margin_grasp"] = trace.margin_grasp
    cols["scale"] = trace.scale
    cols["status"] = trace.status
    cols["objective"] = trace.objective
    cols["eq_residual"] = trace.eq_residual
    cols["bound_violation"] = trace.bound_violation
    cols["kinematics_time_s"] = trace.kinematics_time_s
    cols["assembly_time_s"] = trace.assembly_time_s
    cols["solve_time_s"] = trace.solve_time_s
    cols["step_time_s"] = trace.step_time_s
    # Added with the realised-motion checks (appended: earlier columns keep their place).
    cols["fallback"] = trace.fallback
    cols["sigma_min_l"] = trace.sigma_min_l
    cols["sigma_min_f"] = trace.sigma_min_f
    cols["closure_pos_err_pre"] = trace.closure_pos_err_pre
    cols["closure_rot_err_pre"] = trace.closure_rot_err_pre
    cols["correction_l"] = trace.correction_l
    cols["correction_f"] = trace.correction_f
    cols["feedback_pos"] = trace.feedback_pos
    cols["feedback_rot"] = trace.feedback_rot
    if len(trace) and not np.isnan(trace.grasp_leader).all():  # the leader's grasp slides
        cols["grasp_leader"] = trace.grasp_leader
        cols["m_leader"] = trace.m_leader
        cols["margin_grasp_leader"] = trace.margin_grasp_leader
    if len(trace) and not np.isnan(trace.support_force).all():  # a supporting follower
        cols["support_force"] = trace.support_force
    if len(trace) and not np.isnan(trace.clearance_arm_arm).all():  # a collision scene
        cols["clearance_arm_arm"] = trace.clearance_arm_arm
        cols["clearance_arm_object"] = trace.clearance_arm_object
        cols["clearance_obstacles"] = trace.clearance_obstacles
        if np.isfinite(trace.clearance_self).any():  # arms with self-collision pairs
            cols["clearance_self"] = trace.clearance_self
        cols["clearance_pair"] = trace.clearance_pair
    if len(trace):
        _load_columns(cols, trace)
    return cols


#: The parts of a wrench, in its columns' names.
_WRENCH = ("fx", "fy", "fz", "mx", "my", "mz")


def _load_columns(cols: dict[str, Any], trace: Trace) -> None:
    """Add the load's columns: the planned wrenches, the torques, what was measured."""
    if not np.isnan(trace.f_leader).all():  # a task with a load
        for role, wrench in (("leader", trace.f_leader), ("follower", trace.f_follower)):
            for j, part in enumerate(_WRENCH):
                cols[f"f_{role}_{part}"] = wrench[:, j]
    if not np.isnan(trace.tau_leader).all():  # joint torques recorded
        for role, tau in (("leader", trace.tau_leader), ("follower", trace.tau_follower)):
            for j in range(tau.shape[1]):
                cols[f"tau_{role}_{j + 1}"] = tau[:, j]
    if not np.isnan(trace.internal_force).all():  # wrenches measured
        _measured_columns(cols, trace)


def _measured_columns(cols: dict[str, Any], trace: Trace) -> None:
    """Add the columns of what a plant measured at the hands (:mod:`..control.measured`).

    Against a plant that measures the hands' wrenches (``run --plant mujoco``):
    ``wrench_leader_fx .. wrench_leader_mz`` and ``wrench_follower_fx ..
    wrench_follower_mz`` the measured wrenches (the convention of the ``f_*`` columns),
    ``internal_force`` [N] the size of their internal part and ``internal_follower_fx ..
    internal_follower_mz`` the follower's internal wrench, ``load_share_follower`` the
    follower's share of the load, ``object_x, object_y, object_z`` [m],
    ``object_qw .. object_qz`` the object's measured pose, and ``torque_ratio_measured``
    the largest share of a joint's torque limit the plant's joints reached over the
    sample (NaN without limits).
    """
    for role, wrench in (("leader", trace.wrench_leader), ("follower", trace.wrench_follower)):
        for j, part in enumerate(_WRENCH):
            cols[f"wrench_{role}_{part}"] = wrench[:, j]
    cols["internal_force"] = trace.internal_force
    for j, part in enumerate(_WRENCH):
        cols[f"internal_follower_{part}"] = trace.internal_follower[:, j]
    cols["load_share_follower"] = trace.load_share
    for j, part in enumerate(("x", "y", "z", "qw", "qx", "qy", "qz")):
        cols[f"object_{part}"] = trace.object_pose[:, j]
    cols["torque_ratio_measured"] = trace.torque_ratio_measured


def csv_columns(trace: Trace, extra: dict[str, Any] | None = None) -> dict[str, Any]:
    """Return the columns of the trace's ``trajectory.csv``, in order, SI units.

    :func:`trace_columns`, then ``extra``, further columns (one value per row: a cell's
    record, :mod:`dualarm_qp.cell.record`); a name the trace already has is refused.
    """
    cols = trace_columns(trace)
    for name, values in (extra or {}).items():
        if name in cols or len(values) != len(trace):
            raise InvalidInputError(f"extra column {name!r}: a trace column already has "
                                    f"that name, or it has {len(values)} rows, not "
                                    f"{len(trace)}")
        cols[name] = values
    return cols


def write_trace_csv(path: Path, trace: Trace, extra: dict[str, Any] | None = None, *,
                    columns: dict[str, Any] | None = None) -> None:
    """Write the trace, one row per sample (angles in rad, lengths in m, times in s).

    ``extra`` holds further columns, written after the trace's own
    (:func:`csv_columns`); ``columns``, the columns :func:`csv_columns` returned, if
    they are at hand (``extra`` is then ignored).
    """
    cols = csv_columns(trace, extra) if columns is None else columns
    buf = io.StringIO()
    w = csv.writer(buf)
    w.writerow(cols.keys())
    values = list(cols.values())
    for k in range(len(trace)):
        row = []
        for v in values:
            x = v[k]
            row.append(x if isinstance(x, str) else repr(float(x)))
        w.writerow(row)
    with atomic_open(path) as fh:
        fh.write(buf.getvalue())
