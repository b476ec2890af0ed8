"""Run sweep points where the work is done (a Dask worker, or this process).

:func:`run_batch` is the task a worker receives: a few points, run one after the other
in the worker's process, so that the library is imported once per worker and the
scheduling cost is shared by several rollouts. Each point is built from its document
(:func:`~dualarm_qp.experiments.setup.build_experiment`), rolled out in process with no
files written (:func:`~dualarm_qp.experiments.run.run_experiment` without a folder),
and summed up in one flat *record* (:func:`point_record`, and the realised limits after
the start-up recovery, :mod:`.recovery`): the numbers of the results table. A point
never raises: a library error or a bug becomes a failed record.
"""

from __future__ import annotations

import math
import os
import socket
import time
import traceback
from collections.abc import Sequence
from typing import Any

import numpy as np

from .points import START_UNREACHABLE, PointTask, is_start_failure
from .recovery import FIELDS as RECOVERY_FIELDS
from .recovery import after_recovery

#: The parts whose realised motion is measured against its limits.
PARTS = ("leader", "follower", "grasp")


def _statuses() -> tuple[str, ...]:
    from ..solvers.base import Status

    return tuple(s.value for s in Status)


def _num(value: Any) -> float:
    """Return a float, NaN for None (JSON's null for a non-finite number)."""
    return math.nan if value is None else float(value)


def _nanmin(*values: float) -> float:
    finite = [v for v in values if not math.isnan(v)]
    return min(finite) if finite else math.nan


def _nanmax(*values: float) -> float:
    finite = [v for v in values if not math.isnan(v)]
    return max(finite) if finite else math.nan


def empty_record(status: str, criterion: str | None, message: str) -> dict[str, Any]:
    """Return a record with every number missing (NaN) and no step counted."""
    rec: dict[str, Any] = {
        "status": status, "criterion": criterion, "message": message, "solver": None,
        "samples": 0, "path_completed_pct": 0.0 if status == "failed" else math.nan,
        "time_lost_to_scaling_s": math.nan,
    }
    for part in PARTS:
        rec[f"{part}_range_ratio_max"] = math.nan
        rec[f"{part}_speed_ratio_max"] = math.nan
    rec.update({
        "worst_limit_ratio": math.nan, **dict.fromkeys(RECOVERY_FIELDS, math.nan),
        "joint_margin_min_rad": math.nan,
        "grasp_margin_min_m": math.nan, "closure_pos_err_max_m": math.nan,
        "closure_rot_err_max_rad": math.nan, "leader_pos_err_max_m": math.nan,
        "leader_rot_err_max_rad": math.nan, "step_time_median_s": math.nan,
        "step_time_p99_s": math.nan,
        **{f"steps_{s}": 0 for s in _statuses()},
        "wall_time_s": math.nan, "worker": None,
    })
    return rec


def point_record(summary: dict[str, Any], step_times: Sequence[np.ndarray]) -> dict[str, Any]:
    """Sum one point's run up from its summary (``summary.json``'s content).

    Parameters
    ----------
    summary : dict
        :func:`~dualarm_qp.experiments.run.make_summary` of the first rollout.
    step_times : sequence of ndarray
        Controller step times [s] of every rollout (pooled for the median and p99).
    """
    failure = summary.get("failure") or {}
    rec = empty_record(summary["status"], failure.get("criterion"),
                       summary.get("message", ""))
    rec.update(solver=summary["solver"], samples=int(summary["samples"]),
               path_completed_pct=_num(summary["path_completed_pct"]),
               time_lost_to_scaling_s=_num(summary["time_lost_to_scaling_s"]))
    ratios = []
    for part, r in summary["realised_limits"].items():
        if part in PARTS:
            rec[f"{part}_range_ratio_max"] = _num(r["range_ratio_max"])
            rec[f"{part}_speed_ratio_max"] = _num(r["speed_ratio_max"])
            ratios += [rec[f"{part}_range_ratio_max"], rec[f"{part}_speed_ratio_max"]]
    rec["worst_limit_ratio"] = _nanmax(*ratios)
    rec["joint_margin_min_rad"] = _nanmin(_num(summary["margin_qf_min_rad"]),
                                          _num(summary["margin_ql_min_rad"]))
    rec["grasp_margin_min_m"] = _num(summary["margin_grasp_min_m"])
    for name in ("closure_pos_err_max_m", "closure_rot_err_max_rad", "leader_pos_err_max_m",
                 "leader_rot_err_max_rad"):
        rec[name] = _num(summary[name])
    steps = np.concatenate([np.asarray(s, dtype=float) for s in step_times]) \
        if step_times else np.empty(0)
    steps = steps[np.isfinite(steps)]
    if steps.size:
        rec["step_time_median_s"] = float(np.median(steps))
        rec["step_time_p99_s"] = float(np.percentile(steps, 99))
    for status, count in summary["status_counts"].items():
        rec[f"steps_{status}"] = int(count)
    return rec


def worker_name() -> str:
    """Return the Dask worker's address, or ``host:pid`` outside a worker."""
    try:
        from distributed import get_worker

        return str(get_worker().address)
    except (ImportError, ValueError):
        return f"{socket.gethostname()}:{os.getpid()}"


def run_point(task: PointTask) -> dict[str, Any]:
    """Run one point ``task.repeat`` times; return its record.

    Never raises a library or internal error: those become failed records.
    """
    from ..errors import ConfigError, DualArmError
    from ..experiments.config import parse_config
    from ..experiments.run import run_experiment
    from ..experiments.setup import build_experiment

    t0 = time.perf_counter()
    if task.start_failure is not None:
        rec = empty_record("failed", START_UNREACHABLE, task.start_failure)
    else:
        try:
            exp = build_experiment(parse_config(task.document, task.base_path),
                                   task.base_path)
            outcomes = [run_experiment(exp, None, progress=False, plots=False)
                        for _ in range(task.repeat)]
            rec = point_record(outcomes[0].summary,
                               [o.result.trace.step_time_s for o in outcomes])
            first = outcomes[0].result
            rec.update(after_recovery(first.trace, exp.task, exp.options.grasp_speed_max,
                                      first.dt))
            if any(o.interrupted for o in outcomes):
                rec["status"] = "interrupted"
        except ConfigError as err:
            rec = empty_record("failed", START_UNREACHABLE if is_start_failure(err)
                               else "setup", str(err))
        except DualArmError as err:
            rec = empty_record("failed", "error", f"{type(err).__name__}: {err}")
        except Exception as err:  # a bug: recorded with where it happened, not raised
            where = traceback.extract_tb(err.__traceback__)[-1]
            rec = empty_record("failed", "internal_error",
                               f"{type(err).__name__}: {err} ({where.filename}:"
                               f"{where.lineno})")
    rec["wall_time_s"] = time.perf_counter() - t0
    rec["worker"] = worker_name()
    rec["key"] = task.key
    return rec


def run_batch(tasks: Sequence[PointTask], code: str) -> list[dict[str, Any]]:
    """Run a batch of points in this process (the task a Dask worker runs).

    Parameters
    ----------
    tasks : sequence of PointTask
        The points.
    code : str
        The code digest the driver keys the points with; a worker running other code
        refuses the batch (its numbers would be stored under the wrong key).

    Raises
    ------
    InvalidInputError
        This process's code digest differs from ``code``.
    """
    from ..bench.runner import code_digest
    from ..errors import InvalidInputError

    mine = code_digest()
    if mine != code:
        raise InvalidInputError(f"worker {worker_name()} runs other dualarm_qp code "
                                f"(digest {mine[:12]}, the sweep's is {code[:12]}); install "
                                "the same version on every worker")
    return [run_point(t) for t in tasks]
