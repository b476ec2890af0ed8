"""Run every configuration with every solver; store each finished pair so a bench resumes.

One *job* is one (configuration, solver) pair. It does two things:

1. **Rollouts** of the experiment with the solver (``repeat`` times; the timings of all
   repeats are pooled, the other numbers come from the first, which is deterministic).
   They give the success rate, the status counts, the whole controller step time and its
   split (kinematics of both arms / assembly / solve / verify), the worst residuals,
   the closure error and the joint margins.
2. A **replay** of the configuration's *canonical steps*: the step problems met along
   the rollout of the exact ``nullspace`` solver. Every solver sees exactly these
   problems, so their objectives can be compared step by step (the objective gap to
   the best solver is computed across jobs in :mod:`.report`). For ``qp:*`` solvers the
   replay also times the backend's bare solve (the native call alone, as qpsolvers
   times it) on the same problem with the same warm start and options.

A job's result is keyed by (configuration file and content, solver, settings) and
appended to ``results.jsonl`` as soon as it is finished; a bench run into the same
folder skips every job whose key is already stored.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import os
import platform
import time
import warnings
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .. import __version__
from ..control.controller import ControlOutput, DualArmController
from ..control.rollout import rollout
from ..errors import DualArmError, InvalidInputError
from ..experiments.config import load_config
from ..experiments.setup import Experiment, build_experiment
from ..solvers.base import DEFAULT_TOLERANCE, Status, Tolerance, verify
from ..solvers.policy import solve_step
from ..solvers.registry import get_solver, solver_info
from ..step.build import DualArmState
from ..step.problem import StepProblem
from .store import append_result, load_results

FloatArray = NDArray[np.float64]

#: Every step status, in the order of the status-count columns.
STATUSES: tuple[str, ...] = tuple(s.value for s in Status)

#: Solver whose rollout defines the canonical steps of a configuration (exact, always
#: installed, deterministic).
CANONICAL_SOLVER = "nullspace"

#: Bumped when a job's record changes meaning, so stale stored results are not reused.
RECORD_FORMAT = 1

RESULTS_FILE = "results.jsonl"


@dataclass(frozen=True)
class BenchSettings:
    """Settings that change a job's numbers (they are part of its key).

    Parameters
    ----------
    repeat : int
        Rollouts per job; their step timings are pooled.
    duration : float, optional
        Override of every configuration's run length [s] (None: as configured).
    tolerance : Tolerance
        What counts as meeting the equality and the bounds.
    replay : bool
        Replay the canonical steps (objective gap, bare backend time).
    """

    repeat: int = 1
    duration: float | None = None
    tolerance: Tolerance = DEFAULT_TOLERANCE
    replay: bool = True

    def __post_init__(self) -> None:
        if not (isinstance(self.repeat, int) and self.repeat >= 1):
            raise InvalidInputError(f"repeat must be an integer >= 1, got {self.repeat!r}")
        if self.duration is not None and not (math.isfinite(self.duration)
                                              and self.duration > 0):
            raise InvalidInputError(f"duration must be a positive number of seconds, got "
                                    f"{self.duration}")

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready form (what the key hashes)."""
        return {"repeat": self.repeat, "duration_s": self.duration,
                "tol_equality": self.tolerance.equality, "tol_bounds": self.tolerance.bounds,
                "replay": self.replay}


@dataclass(frozen=True)
class BenchConfig:
    """A configuration file read once: its path, text hash and built experiment."""

    path: str
    name: str
    sha256: str


@dataclass
class BenchResult:
    """What :func:`run_bench` did.

    Attributes
    ----------
    records : list of dict
        One record per (configuration, solver), in request order.
    computed : int
        Jobs computed in this call (the others were read back from the store).
    out_dir : Path
        Folder of ``results.jsonl``.
    machine : dict
        Where and when the jobs of this call ran.
    """

    records: list[dict[str, Any]]
    computed: int
    out_dir: Path
    machine: dict[str, Any] = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        """Whether every job ran to its end (a solver failing steps is still ok)."""
        return all(not r.get("error") for r in self.records)


def settings_hash(config: BenchConfig, solver: str, settings: BenchSettings) -> str:
    """Key of one job: hash of the configuration text, solver, settings and format."""
    blob = json.dumps({"config": config.path, "config_sha256": config.sha256,
                       "solver": solver, "settings": settings.as_dict(),
                       "format": RECORD_FORMAT, "version": __version__}, sort_keys=True)
    return hashlib.sha256(blob.encode()).hexdigest()[:16]


def read_config(path: str | Path) -> BenchConfig:
    """Validate a configuration file (raises ConfigError, exit code 2 in the CLI)."""
    p = Path(path)
    cfg = load_config(p)
    return BenchConfig(str(path), cfg.name, hashlib.sha256(p.read_bytes()).hexdigest())


def check_solvers(names: Sequence[str]) -> list[str]:
    """Return ``names`` after checking each is registered and installed.

    Raises
    ------
    SolverNotFoundError
        Naming the pip extra for a known solver whose backend is missing.
    """
    if not names:
        raise InvalidInputError("no solver given")
    for name in names:
        solver_info(name)
    return list(dict.fromkeys(names))


def machine_info() -> dict[str, Any]:
    """Describe the machine and its load, for the report."""
    cpu = platform.processor() or ""
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as fh:
            for line in fh:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    try:
        load = list(os.getloadavg())
    except OSError:
        load = []
    import qpsolvers

    return {"cpu": cpu, "cpus": os.cpu_count(), "system": platform.platform(),
            "python": platform.python_version(), "numpy": np.__version__,
            "qpsolvers": qpsolvers.__version__, "dualarm_qp": __version__,
            "load_average": load, "time": time.strftime("%Y-%m-%d %H:%M:%S %z")}


class _RecordingController(DualArmController):
    """A controller that keeps the step problem of every step it computes."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.problems: list[StepProblem] = []

    def step(self, state: DualArmState, *, scale_max: float = 1.0) -> ControlOutput:
        out = super().step(state, scale_max=scale_max)
        if out.build is not None:
            self.problems.append(out.build.problem)
        return out


def _experiment(config: BenchConfig, solver: str, settings: BenchSettings) -> Experiment:
    exp = build_experiment(load_config(config.path), config.path, solver=solver)
    if settings.duration is not None:
        exp = dataclasses.replace(exp, duration=settings.duration)
    return exp


def canonical_steps(config: BenchConfig, settings: BenchSettings) -> list[StepProblem]:
    """Step problems met along the configuration's rollout with the exact solver."""
    exp = _experiment(config, CANONICAL_SOLVER, settings)
    ctrl = _RecordingController(exp.task, get_solver(CANONICAL_SOLVER, **_opts(exp)),
                                exp.options, leader_gain=exp.leader_gain, policy=exp.policy,
                                tolerance=settings.tolerance)
    rollout(ctrl, exp.initial, duration=exp.duration, project=exp.project, limits=exp.limits)
    return ctrl.problems


def _opts(exp: Experiment) -> dict[str, Any]:
    """Return the configured solver options if the configured solver is the canonical one."""
    return dict(exp.solver_options) if exp.solver_name == CANONICAL_SOLVER else {}


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
    """Run one (configuration, solver) job and return its record (see module docstring)."""
    t_start = time.perf_counter()
    exp = _experiment(config, solver, settings)
    opts = exp.solver_options if solver == exp.solver_name else {}
    planned = math.floor(exp.duration / exp.options.dt + 1e-9) + 1
    runs = []
    for _ in range(settings.repeat):
        ctrl = DualArmController(exp.task, get_solver(solver, **opts), exp.options,
                                 leader_gain=exp.leader_gain, policy=exp.policy,
                                 tolerance=settings.tolerance)
        runs.append(rollout(ctrl, exp.initial, duration=exp.duration, project=exp.project,
                            limits=exp.limits))
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
    hard = solver_info(solver).hard_bounds
    bare = _BareProbe.make(s)
    objective: list[float | None] = []
    times: list[float] = []
    bare_times: list[float] = []
    for problem in steps:
        t0 = time.perf_counter()
        sol = solve_step(s, problem, policy=exp.policy, tol=tol)
        t1 = time.perf_counter()
        sol = verify(problem, sol, tol, claims_bounds=hard)
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


class _BareProbe:
    """Call a ``qp:*`` solver's backend through qpsolvers alone and read its solve time.

    The QP is built exactly as :class:`~dualarm_qp.solvers.qp.QPSolver` builds it (same
    shift, matrix format, options and warm start) outside the timed region; the time is
    the one qpsolvers measures around the backend's own call.
    """

    def __init__(self, solver: Any) -> None:
        self.solver = solver

    @classmethod
    def make(cls, solver: Any) -> _BareProbe | None:
        if not str(getattr(solver, "name", "")).startswith("qp:"):
            return None
        if not (hasattr(solver, "backend") and hasattr(solver, "options")):
            return None
        return cls(solver)

    def solve_time(self, problem: StepProblem) -> float | None:
        import qpsolvers
        import scipy.sparse as sp

        backend = self.solver.backend
        if (problem.lower > problem.upper).any():
            return None
        c = problem.center
        P: Any = np.diag(problem.weights)
        A: Any = problem.A
        if backend.sparse:
            P, A = sp.csc_matrix(P), sp.csc_matrix(A)
        qp = qpsolvers.Problem(P, np.zeros(problem.n), A=A, b=problem.b - problem.A @ c,
                               lb=problem.lower - c, ub=problem.upper - c)
        initvals = None
        if backend.warm_start and problem.x_prev is not None:
            initvals = problem.x_prev - c
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                res = qpsolvers.solve_problem(qp, solver=backend.solver, initvals=initvals,
                                              **self.solver.options)
        except Exception:  # a backend failure is the solver's business, not the probe's
            return None
        t = getattr(res, "solve_time", None)
        return float(t) if t is not None else None


def run_bench(
    configs: Sequence[str | Path],
    solvers: Sequence[str],
    out_dir: str | Path,
    *,
    settings: BenchSettings | None = None,
    log: Callable[[str], None] | None = None,
    job: Callable[..., dict[str, Any]] = run_job,
) -> BenchResult:
    """Run every configuration with every solver; reuse the jobs already stored.

    Parameters
    ----------
    configs : sequence of path
        Experiment files (validated before any job runs).
    solvers : sequence of str
        Registry names (checked before any job runs).
    out_dir : path
        Folder of the result store ``results.jsonl``.
    settings : BenchSettings, optional
        Repeat count, duration override, tolerance.
    log : callable, optional
        Receives one line per job.
    job : callable
        The job function (tests replace it to count or interrupt jobs).

    Returns
    -------
    BenchResult
        Records in (configuration, solver) order. A job that raised a library error is
        stored with an ``"error"`` message and is not retried on resume; an interrupt
        (Ctrl-C) stops the bench with every finished job stored.
    """
    settings = settings or BenchSettings()
    solvers = check_solvers(solvers)
    cfgs = [read_config(p) for p in configs]
    if not cfgs:
        raise InvalidInputError("no configuration given")
    out = Path(out_dir)
    store = out / RESULTS_FILE
    done = load_results(store)
    records: list[dict[str, Any]] = []
    computed = 0
    machine = machine_info()
    for cfg in cfgs:
        canonical: list[StepProblem] | None = None
        for solver in solvers:
            key = settings_hash(cfg, solver, settings)
            if key in done:
                records.append(done[key])
                if log:
                    log(f"{cfg.name} / {solver}: stored result reused")
                continue
            if canonical is None and settings.replay:
                canonical = canonical_steps(cfg, settings)
            try:
                rec = job(cfg, solver, settings, canonical)
            except DualArmError as err:
                rec = {"config": cfg.path, "experiment": cfg.name, "solver": solver,
                       "error": f"{type(err).__name__}: {err}"}
            rec.update(key=key, settings=settings.as_dict(), machine=machine)
            append_result(store, rec)
            done[key] = rec
            records.append(rec)
            computed += 1
            if log:
                log(_line(rec))
    return BenchResult(records, computed, out, machine)


def _line(rec: dict[str, Any]) -> str:
    if rec.get("error"):
        return f"{rec['experiment']} / {rec['solver']}: ERROR {rec['error']}"
    return (f"{rec['experiment']} / {rec['solver']}: success {rec['success_rate']:.3f}, "
            f"step median {rec['step_time_median_s'] * 1e6:.0f} us")
