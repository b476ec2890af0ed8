"""Writing run outputs: CSV trace, JSON summary, plots. Every file is written atomically.

A file is written to a temporary name in the same folder and renamed into place, so a
run that fails or is interrupted never leaves a half-written file behind: a reader sees
either the previous complete file or the new complete one.
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
import tempfile
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import IO, Any

import numpy as np

from ..control.rollout import Trace


def _umask_mode() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return 0o666 & ~mask


@contextmanager
def atomic_open(path: Path) -> Iterator[IO[str]]:
    """Open a temporary text file beside ``path``; rename it onto ``path`` on success."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8", newline="") as fh:
            yield fh
        os.chmod(tmp, _umask_mode())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise


def atomic_write_with(path: Path, writer: Callable[[str], None]) -> None:
    """Let ``writer(tmp_path)`` write a file (e.g. a plot), then rename it onto ``path``."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=path.suffix, dir=path.parent)
    os.close(fd)
    try:
        writer(tmp)
        os.chmod(tmp, _umask_mode())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise


def _jsonable(value: Any) -> Any:
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return _jsonable(value.tolist())
    if isinstance(value, (np.floating, float)):
        f = float(value)
        return f if math.isfinite(f) else None
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.bool_):
        return bool(value)
    return value


def write_json(path: Path, data: dict[str, Any]) -> None:
    """Write ``data`` as indented JSON (non-finite numbers become null)."""
    text = json.dumps(_jsonable(data), indent=2, sort_keys=False)
    with atomic_open(path) as fh:
        fh.write(text + "\n")


def trace_columns(trace: Trace) -> dict[str, Any]:
    """Return the CSV columns of a trace, in order, SI units."""
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
    return cols


def write_trace_csv(path: Path, trace: Trace) -> None:
    """Write the trace, one row per sample (angles in rad, lengths in m, times in s)."""
    cols = trace_columns(trace)
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
