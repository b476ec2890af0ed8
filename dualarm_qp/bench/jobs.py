"""One bench job: the rollouts of one (configuration, solver) pair, and the replay.

A job runs the experiment with the solver (``repeat`` times; the timings of all
repeats are pooled, the other numbers come from the first, which is deterministic) and
replays the configuration's canonical steps (:func:`canonical_steps`) with it; see
:mod:`.runner` for how jobs are stored and resumed. A backend that reports that a signal
interrupted its solve voids the job (:class:`BackendInterrupted`).
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections import Counter
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..control.controller import ControlOutput, DualArmController
from ..control.rollout import rollout
from ..experiments.config import load_config
from ..experiments.setup import Experiment, build_experiment
from ..solvers.base import Status, Tolerance
from ..solvers.policy import solve_step
from ..solvers.registry import get_solver
from ..step.problem import StepProblem
from .bare import BareProbe
from .interrupted import BackendInterrupted, backend_interrupted
from .keys import BenchConfig, BenchSettings

FloatArray = NDArray[np.float64]

#: Every step status, in the order of the status-count columns.
STATUSES: tuple[str, ...] = tuple(s.value for s in Status)

#: Solver whose rollout defines the canonical steps of a configuration (exact, always
#: installed, deterministic).
CANONICAL_SOLVER = "nullspace"


def job_failure(rec: dict[str, Any]) -> str | None:
    """Why a job failed, or None: it raised an error, or it had no usable step.

    A job whose run stopped early after some usable steps has not failed: its success
    rate measures the solver. One that raised a library error (``"error"``), or whose
    run produced no usable step (nothing to time or compare), has. A job whose solver
    cannot take the file's limits (``"not_applicable"``: a limit that gives rows with a
    solver that takes boxes only) has not failed either: it was not run.
    """
    if rec.get("not_applicable"):
        return None
    if rec.get("error"):
        return str(rec["error"])
    if not rec.get("steps_run") or not rec.get("success_rate"):
        why = rec.get("message") or "no reason recorded"
        return f"no usable step: {why}"
    return None


def _check_solution(sol: Any) -> None:
    """Raise BackendInterrupted if a step solution shows that a signal cut its solve short."""
    fallback = sol.extras.get("fallback") if isinstance(sol.extras, dict) else None
    texts = (sol.extras.get("backend_status", "") if isinstance(sol.extras, dict) else "",
             sol.message, fallback.get("message", "") if isinstance(fallback, dict) else "")
    if any(backend_interrupted(t) for t in texts):
        raise BackendInterrupted(f"{sol.solver}: a signal interrupted the backend "
                                 f"({sol.message})")


def _check_output(out: ControlOutput) -> None:
    """Refuse a controller step answered by a backend that a signal interrupted."""
    _check_solution(out.solution)


def _controller(exp: Experiment, settings: BenchSettings,
                on_step: Callable[[ControlOutput], None] = _check_output) -> DualArmController:
    """Return the experiment's controller as the bench runs it.

    With the bench's tolerance and no fallback (each solver's own success is measured);
    ``on_step`` (default: refuse an answer of an interrupted backend) sees every step.
    """
    return exp.controller(fallback=False, tolerance=settings.tolerance, on_step=on_step)


def _experiment(config: BenchConfig, solver: str, settings: BenchSettings) -> Experiment:
    exp = build_experiment(load_config(config.path), config.path, solver=solver,
                           solver_options=settings.solver_options)
    if settings.duration is not None:
        exp = dataclasses.replace(exp, duration=settings.duration)
    return exp


def canonical_steps(config: BenchConfig, settings: BenchSettings) -> list[StepProblem]:
    """Step problems met along the configuration's rollout with the exact solver."""
    exp = _experiment(config, CANONICAL_SOLVER, settings)
    problems: list[StepProblem] = []

    def keep(out: ControlOutput) -> None:
        _check_output(out)
        if out.build is not None:
            problems.append(out.build.problem)

    rollout(_controller(exp, settings, keep), exp.initial, duration=exp.duration,
            project=exp.project, limits=exp.limits, initial_rates=exp.start_rates())
    return problems


def _stats(values: FloatArray, prefix: str) -> dict[str, float]:
    v = values[np.isfinite(values)]
    if not v.size:
        return {f"{prefix}_median_s": float("nan"), f"{prefix}_p99_s": float("nan")}
    return {f"{prefix}_median_s": float(np.median(v)),
            f"{prefix}_p99_s": float(np.percentile(v, 99))}


def _fmin(a: FloatArray) -> float:
    return float(np.nanmin(a)) if a.size and not np.isnan(a).all() else float("nan")


def _fmax(a: FloatArray) -> float:
    return float(np.nanmax(a)) if a.size and not np.isnan(a).all() else float("nan")


def run_job(config: BenchConfig, solver: str, settings: BenchSettings,
            canonical: Sequence[StepProblem] | None = None) -> dict[str, Any]:
    """Run one (configuration, solver) job and return its record (see module docstring).

    Raises
    ------
    BackendInterrupted
        A backend reported that a signal interrupted one of its solves: the job's numbers
        are void (the caller must not store them).
    """
    t_start = time.perf_counter()
    exp = _experiment(config, solver, settings)
    opts = exp.solver_options
    planned = math.floor(exp.duration / exp.options.dt + 1e-9) + 1
    runs = []
    start = exp.start_rates()
    for _ in range(settings.repeat):
        runs.append(rollout(_controller(exp, settings), exp.initial, duration=exp.duration,
                            project=exp.project, limits=exp.limits, initial_rates=start))
    first = runs[0]
    tr = first.trace
    planned = max(planned, len(tr))  # a slowed task runs past its nominal samples
    counts = Counter(tr.status)
    usable = sum(counts.get(s.value, 0) for s in Status if s.usable)
    k_all, a_all, s_all, t_all = (
        np.concatenate([getattr(r.trace, name) for r in runs])
        for name in ("kinematics_time_s", "assembly_time_s", "solve_time_s", "step_time_s"))
    rec: dict[str, Any] = {
        "config": config.path,
        "experiment": config.name,
        "solver": solver,
        "completed": bool(first.completed),
        "message": first.message,
        "success_rate": usable / planned,
        "steps": planned,
        "steps_run": len(tr),
        **{f"status_{s}": int(counts.get(s, 0)) for s in STATUSES},
        "status_not_run": planned - len(tr),
        **_stats(t_all, "step_time"),
        **_stats(k_all, "kinematics_time"),
        **_stats(a_all, "assembly_time"),
        **_stats(s_all, "solve_time"),
        **_stats(t_all - k_all - a_all - s_all, "verify_time"),
        "bound_violation_max": _fmax(tr.bound_violation),
        "eq_residual_max": _fmax(tr.eq_residual),
        "closure_pos_err_max_m": _fmax(tr.closure_pos_err),
        "closure_rot_err_max_rad": _fmax(tr.closure_rot_err),
        "margin_qf_min_rad": _fmin(tr.margin_qf),
        "margin_ql_min_rad": _fmin(tr.margin_ql),
        "margin_grasp_min_m": _fmin(tr.margin_grasp),
        "timed_samples": int(np.isfinite(t_all).sum()),
    }
    if settings.replay:
        steps = canonical if canonical is not None else canonical_steps(config, settings)
        rec.update(replay(steps, solver, opts, exp, settings.tolerance))
    rec["wall_time_s"] = time.perf_counter() - t_start
    return rec


def replay(steps: Sequence[StepProblem], solver: str, options: dict[str, Any],
           exp: Experiment, tol: Tolerance) -> dict[str, Any]:
    """Solve the canonical ``steps`` in order, as the controller would; time each solve.

    Returns the objective per step (None where the step was not solved within ``tol``)
    and the solve-time median; for ``qp:*`` solvers also the backend's bare solve time.
    """
    s = get_solver(solver, **options)
    bare = BareProbe.make(s)
    objective: list[float | None] = []
    times: list[float] = []
    bare_times: list[float] = []
    for problem in steps:
        t0 = time.perf_counter()
        sol = solve_step(s, problem, policy=exp.policy, tol=tol)  # certified with tol
        t1 = time.perf_counter()
        _check_solution(sol)
        times.append(t1 - t0)
        ok = sol.status.usable and sol.scale == 1.0
        objective.append(sol.objective if ok else None)
        if bare is not None:
            bt = bare.solve_time(problem)
            if bt is not None:
                bare_times.append(bt)
    t = np.asarray(times)
    solved = sum(o is not None for o in objective)
    out: dict[str, Any] = {
        "replay_steps": len(steps),
        "replay_success_rate": solved / len(steps) if steps else float("nan"),
        "replay_solve_time_median_s": float(np.median(t)) if t.size else float("nan"),
        "replay_objective": objective,
        "bare_solve_time_median_s": float("nan"),
        "solve_over_bare": float("nan"),
    }
    if bare_times:
        bm = float(np.median(bare_times))
        out["bare_solve_time_median_s"] = bm
        out["solve_over_bare"] = out["replay_solve_time_median_s"] / bm
    return out


__all__ = ["CANONICAL_SOLVER", "STATUSES", "canonical_steps", "job_failure", "replay",
           "run_job"]
