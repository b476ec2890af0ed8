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

A job's result is keyed by (configuration file and content, solver, settings, record
format, and a digest of the package's source code, :func:`code_digest`) and appended to
``results.jsonl`` as soon as it is finished; a bench run into the same folder skips
every job whose key is already stored, so changed code is measured afresh.

Interrupts and sharing (see :mod:`dualarm_qp._signals` and :mod:`.store`): a job cut
short by SIGINT or SIGTERM, or whose backend reports that a signal interrupted a solve
(:class:`BackendInterrupted`), is never stored, and a finished job is stored whole (under
a :class:`~dualarm_qp._signals.SignalHold`); the bench stops with what finished
(:class:`BenchInterrupted`). Benches run together on one folder claim each job before
computing it, so every job is computed and stored once; a bench waits for the jobs
another one is computing.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import json
import math
import os
import platform
import re
import signal
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
from .._signals import (
    Interrupted,
    InterruptHandlers,
    SignalHold,
    pass_on_sigint,
    raise_if_interrupted,
    signal_name,
)
from ..control.controller import ControlOutput, DualArmController
from ..control.rollout import rollout
from ..errors import DualArmError, InvalidInputError, PairingError
from ..experiments.config import load_config
from ..experiments.options import options_for
from ..experiments.setup import Experiment, build_experiment
from ..solvers.base import DEFAULT_TOLERANCE, Status, Tolerance
from ..solvers.policy import solve_step
from ..solvers.registry import get_solver, solver_info
from ..step.problem import StepProblem
from .store import append_result, claim_job, load_results

FloatArray = NDArray[np.float64]

#: Every step status, in the order of the status-count columns.
STATUSES: tuple[str, ...] = tuple(s.value for s in Status)

#: Solver whose rollout defines the canonical steps of a configuration (exact, always
#: installed, deterministic).
CANONICAL_SOLVER = "nullspace"

#: Bumped when a job's record changes meaning, so stale stored results are not reused.
RECORD_FORMAT = 1

RESULTS_FILE = "results.jsonl"

#: How often a job is run again when its backend reported an interrupt that the process
#: ignores (SIGINT inherited as ignored: osqp still catches it during a solve).
BACKEND_INTERRUPT_RETRIES = 2

_INTERRUPT_WORDS = re.compile(r"\binterrupt", re.IGNORECASE)


@functools.lru_cache(maxsize=1)
def code_digest() -> str:
    """Digest of the package's Python source: sha256 over sorted relative paths + contents.

    Computed once per process; part of every job's key, so that stored results of other
    code are not reused.
    """
    root = Path(__file__).resolve().parents[1]
    h = hashlib.sha256()
    for path in sorted(root.rglob("*.py"), key=lambda p: p.relative_to(root).as_posix()):
        h.update(path.relative_to(root).as_posix().encode() + b"\0")
        h.update(path.read_bytes() + b"\0")
    return h.hexdigest()


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
    solver_options : dict
        Options per solver name (``--solver-option``), applied over a configuration's
        own options when that solver runs; part of that solver's job keys only.
    """

    repeat: int = 1
    duration: float | None = None
    tolerance: Tolerance = DEFAULT_TOLERANCE
    replay: bool = True
    solver_options: dict[str, dict[str, Any]] = field(default_factory=dict, hash=False)

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
    planned: int = 0
    interrupted: str | None = None

    @property
    def failures(self) -> list[tuple[dict[str, Any], str]]:
        """The failed jobs (see :func:`job_failure`) with their reasons."""
        out = []
        for rec in self.records:
            reason = job_failure(rec)
            if reason is not None:
                out.append((rec, reason))
        return out

    @property
    def ok(self) -> bool:
        """Whether every job ran and measured something (a solver failing steps is ok)."""
        return not self.failures and self.interrupted is None


class BenchInterrupted(Interrupted):
    """:func:`run_bench` was interrupted; :attr:`result` holds the jobs that finished.

    Parameters
    ----------
    result : BenchResult
        The finished jobs (stored or read back), in request order.
    signum : int or None
        The signal, where known.
    """

    def __init__(self, result: BenchResult, signum: int | None) -> None:
        super().__init__(signum)
        self.result = result


class BackendInterrupted(Exception):
    """A backend reported that a signal interrupted its solve (the job's numbers are void)."""


def backend_interrupted(status: Any) -> bool:
    """Whether a backend status or message says that a signal interrupted the solve.

    osqp reports ``"interrupted"`` (``OSQP_SIGINT``) when its own SIGINT handler caught a
    Ctrl-C during the solve; its answer then carries no solution.
    """
    return bool(_INTERRUPT_WORDS.search(str(status)))


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


def settings_hash(config: BenchConfig, solver: str, settings: BenchSettings) -> str:
    """Key of one job: hash of the configuration text, solver, settings, format and code."""
    key = {"config": config.path, "config_sha256": config.sha256,
           "solver": solver, "settings": settings.as_dict(),
           "format": RECORD_FORMAT, "version": __version__,
           "code": code_digest()}
    options = options_for(solver, settings.solver_options)
    if options:  # only this solver's command-line options
        key["solver_options"] = options
    blob = json.dumps(key, sort_keys=True)
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
        from ..solvers import available_solvers

        raise InvalidInputError("no solver given; available solvers: "
                                + ", ".join(available_solvers()))
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
    bare = _BareProbe.make(s)
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
        if problem.has_empty_box():
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
        except Exception as err:  # a backend failure is the solver's business, not the probe's
            if backend_interrupted(err):
                pass_on_sigint()
                raise BackendInterrupted(f"bare {backend.solver}: {err}") from None
            return None
        if backend_interrupted(_probe_status(res)):
            # osqp's own SIGINT handler caught a Ctrl-C during the solve and qpsolvers does
            # not pass it on: hand it to Python (raises unless SIGINT is ignored).
            pass_on_sigint()
            raise BackendInterrupted(f"bare {backend.solver}: {_probe_status(res)}")
        t = getattr(res, "solve_time", None)
        return float(t) if t is not None else None


def _probe_status(res: Any) -> str:
    """Return a qpsolvers solution's backend status as text ('' if none)."""
    extras = getattr(res, "extras", None) or {}
    if "status" in extras:
        return str(extras["status"])
    info = extras.get("info")
    return str(getattr(info, "status", "")) if info is not None else ""


def run_bench(
    configs: Sequence[str | Path],
    solvers: Sequence[str],
    out_dir: str | Path,
    *,
    settings: BenchSettings | None = None,
    log: Callable[[str], None] | None = None,
    job: Callable[..., dict[str, Any]] | None = None,
) -> BenchResult:
    """Run every configuration with every solver; reuse the jobs already stored.

    Parameters
    ----------
    configs : sequence of path
        Experiment files (validated before any job runs).
    solvers : sequence of str
        Registry names (checked before any job runs).
    out_dir : path
        Folder of the result store ``results.jsonl``; other benches may use it at the
        same time (each job is computed and stored once, see :mod:`.store`).
    settings : BenchSettings, optional
        Repeat count, duration override, tolerance.
    log : callable, optional
        Receives a line when the jobs start and one line per job.
    job : callable, optional
        The job function (default :func:`run_job`; tests replace it to count or
        interrupt jobs).

    Returns
    -------
    BenchResult
        Records in (configuration, solver) order. A job that raised a library error is
        stored with an ``"error"`` message and is not retried on resume.

    Raises
    ------
    BenchInterrupted
        On SIGINT (Ctrl-C) or SIGTERM, or a KeyboardInterrupt: the job under way is not
        stored; the exception's ``result`` holds the jobs that finished.
    """
    settings = settings or BenchSettings()
    solvers = check_solvers(solvers)
    cfgs = [read_config(p) for p in configs]
    if not cfgs:
        raise InvalidInputError("no configuration given")
    job_fn = run_job if job is None else job
    out = Path(out_dir)
    store = out / RESULTS_FILE
    machine = machine_info()
    pairs = [(cfg, solver, settings_hash(cfg, solver, settings))
             for cfg in cfgs for solver in solvers]
    finished: dict[str, dict[str, Any]] = {}
    computed = 0
    canonical: dict[str, list[StepProblem]] = {}

    def say(line: str) -> None:
        if log:
            log(line)

    def result(interrupted: str | None = None) -> BenchResult:
        recs = [finished[k] for _, _, k in pairs if k in finished]
        return BenchResult(recs, computed, out, machine, planned=len(pairs),
                           interrupted=interrupted)

    def compute(cfg: BenchConfig, solver: str, key: str) -> dict[str, Any]:
        for attempt in range(BACKEND_INTERRUPT_RETRIES + 1):
            try:
                if settings.replay and cfg.path not in canonical:
                    canonical[cfg.path] = canonical_steps(cfg, settings)
                rec = job_fn(cfg, solver, settings, canonical.get(cfg.path))
            except PairingError as err:  # the file's limits are not this solver's kind
                rec = {"config": cfg.path, "experiment": cfg.name, "solver": solver,
                       "not_applicable": str(err)}
            except DualArmError as err:
                rec = {"config": cfg.path, "experiment": cfg.name, "solver": solver,
                       "error": f"{type(err).__name__}: {err}"}
            except BackendInterrupted as err:
                # Only reached when SIGINT is ignored here (otherwise the interrupt was
                # raised): the process goes on, but this attempt's numbers are void.
                raise_if_interrupted()
                if attempt == BACKEND_INTERRUPT_RETRIES:  # someone keeps sending SIGINT
                    raise Interrupted(signal.SIGINT) from err
                say(f"{cfg.name} / {solver}: {err}; running the job again")
                continue
            raise_if_interrupted()  # an interrupt that was swallowed on the way still counts
            rec.update(key=key, settings=settings.as_dict(), machine=machine,
                       code=code_digest())
            return rec
        raise AssertionError("unreachable")  # pragma: no cover

    def run_one(cfg: BenchConfig, solver: str, key: str, wait: bool) -> bool:
        """Run one job unless stored or claimed elsewhere; False if left to another bench."""
        nonlocal computed
        if wait:
            say(f"{cfg.name} / {solver}: waiting for the bench that is computing it")
        claim = claim_job(out, key, wait=wait)
        if claim is None:
            return False
        with claim:
            stored = load_results(store).get(key)  # another bench may have stored it
            if stored is not None:
                finished[key] = stored
                claim.release(stored=True)
                say(f"{cfg.name} / {solver}: stored by another bench, reused")
                return True
            rec = compute(cfg, solver, key)
            with SignalHold():  # a finished job is stored whole, or not at all
                append_result(store, rec)
                claim.release(stored=True)
                finished[key] = rec
                computed += 1
                say(_line(rec))
        return True

    with InterruptHandlers() as handlers:
        try:
            done = load_results(store)
            for _, _, key in pairs:
                if key in done:
                    finished[key] = done[key]
            todo = len({k for _, _, k in pairs} - finished.keys())
            say(f"bench: {len(pairs)} jobs, {len(pairs) - todo} stored in {store}, "
                f"{todo} to run")
            later = []
            for cfg, solver, key in pairs:
                if key in finished:
                    if key in done:
                        say(f"{cfg.name} / {solver}: stored result reused")
                    continue
                if not run_one(cfg, solver, key, wait=False):
                    say(f"{cfg.name} / {solver}: another bench is computing it")
                    later.append((cfg, solver, key))
            for cfg, solver, key in later:
                if key not in finished:
                    run_one(cfg, solver, key, wait=True)
        except KeyboardInterrupt as err:
            signum = handlers.signum or getattr(err, "signum", None)
            raise BenchInterrupted(result(signal_name(signum)), signum) from None
    return result()


def _line(rec: dict[str, Any]) -> str:
    if rec.get("not_applicable"):
        return f"{rec['experiment']} / {rec['solver']}: not applicable: {rec['not_applicable']}"
    reason = job_failure(rec)
    if reason is not None:
        return f"{rec['experiment']} / {rec['solver']}: FAILED: {reason}"
    return (f"{rec['experiment']} / {rec['solver']}: success {rec['success_rate']:.3f}, "
            f"step median {rec['step_time_median_s'] * 1e6:.0f} us")
