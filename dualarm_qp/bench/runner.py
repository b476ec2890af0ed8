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
format, and a digest of the package's source code, :func:`~.keys.code_digest`) and
appended to ``results.jsonl`` as soon as it is finished; a bench run into the same folder
skips every job whose key is already stored, so changed code is measured afresh. A job
is :mod:`.jobs`, its key :mod:`.keys`.

Interrupts and sharing (see :mod:`dualarm_qp._signals` and :mod:`.store`): a job cut
short by SIGINT or SIGTERM, or whose backend reports that a signal interrupted a solve
(:class:`BackendInterrupted`), is never stored, and a finished job is stored whole (under
a :class:`~dualarm_qp._signals.SignalHold`); the bench stops with what finished
(:class:`BenchInterrupted`). Benches run together on one folder claim each job before
computing it, so every job is computed and stored once; a bench waits for the jobs
another one is computing.
"""

from __future__ import annotations

import signal
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .._signals import (
    Interrupted,
    InterruptHandlers,
    SignalHold,
    raise_if_interrupted,
    signal_name,
)
from ..errors import DualArmError, InvalidInputError, PairingError
from ..step.problem import StepProblem
from .interrupted import BackendInterrupted, backend_interrupted
from .jobs import CANONICAL_SOLVER, STATUSES, canonical_steps, job_failure, replay, run_job
from .keys import (
    RECORD_FORMAT,
    BenchConfig,
    BenchSettings,
    check_solvers,
    code_digest,
    machine_info,
    read_config,
    settings_hash,
)
from .store import append_result, claim_job, load_results

RESULTS_FILE = "results.jsonl"

#: How often a job is run again when its backend reported an interrupt that the process
#: ignores (SIGINT inherited as ignored: osqp still catches it during a solve).
BACKEND_INTERRUPT_RETRIES = 2


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
    bench = _Bench(cfgs, solvers, Path(out_dir), settings, log,
                   run_job if job is None else job)
    return bench.run()


class _Bench:
    """One call of :func:`run_bench`: its jobs, the store, what this call computed."""

    def __init__(self, cfgs: Sequence[BenchConfig], solvers: Sequence[str], out: Path,
                 settings: BenchSettings, log: Callable[[str], None] | None,
                 job: Callable[..., dict[str, Any]]) -> None:
        self.settings, self.log, self.job = settings, log, job
        self.out = out
        self.store = out / RESULTS_FILE
        self.machine = machine_info()
        self.pairs = [(cfg, solver, settings_hash(cfg, solver, settings))
                      for cfg in cfgs for solver in solvers]
        self.finished: dict[str, dict[str, Any]] = {}
        self.computed = 0
        self.canonical: dict[str, list[StepProblem]] = {}

    def say(self, line: str) -> None:
        """Hand one line to the log, if any."""
        if self.log:
            self.log(line)

    def result(self, interrupted: str | None = None) -> BenchResult:
        """Return the finished jobs, in request order."""
        recs = [self.finished[k] for _, _, k in self.pairs if k in self.finished]
        return BenchResult(recs, self.computed, self.out, self.machine,
                           planned=len(self.pairs), interrupted=interrupted)

    def run(self) -> BenchResult:
        """Run the jobs not stored yet, then wait for those another bench is computing."""
        with InterruptHandlers() as handlers:
            try:
                done = load_results(self.store)
                for _, _, key in self.pairs:
                    if key in done:
                        self.finished[key] = done[key]
                todo = len({k for _, _, k in self.pairs} - self.finished.keys())
                self.say(f"bench: {len(self.pairs)} jobs, {len(self.pairs) - todo} stored in "
                         f"{self.store}, {todo} to run")
                later = []
                for cfg, solver, key in self.pairs:
                    if key in self.finished:
                        if key in done:
                            self.say(f"{cfg.name} / {solver}: stored result reused")
                        continue
                    if not self.run_one(cfg, solver, key, wait=False):
                        self.say(f"{cfg.name} / {solver}: another bench is computing it")
                        later.append((cfg, solver, key))
                for cfg, solver, key in later:
                    if key not in self.finished:
                        self.run_one(cfg, solver, key, wait=True)
            except KeyboardInterrupt as err:
                signum = handlers.signum or getattr(err, "signum", None)
                raise BenchInterrupted(self.result(signal_name(signum)), signum) from None
        return self.result()

    def run_one(self, cfg: BenchConfig, solver: str, key: str, wait: bool) -> bool:
        """Run one job unless stored or claimed elsewhere; False if left to another bench."""
        if wait:
            self.say(f"{cfg.name} / {solver}: waiting for the bench that is computing it")
        claim = claim_job(self.out, key, wait=wait)
        if claim is None:
            return False
        with claim:
            stored = load_results(self.store).get(key)  # another bench may have stored it
            if stored is not None:
                self.finished[key] = stored
                claim.release(stored=True)
                self.say(f"{cfg.name} / {solver}: stored by another bench, reused")
                return True
            rec = self.compute(cfg, solver, key)
            with SignalHold():  # a finished job is stored whole, or not at all
                append_result(self.store, rec)
                claim.release(stored=True)
                self.finished[key] = rec
                self.computed += 1
                self.say(_line(rec))
        return True

    def compute(self, cfg: BenchConfig, solver: str, key: str) -> dict[str, Any]:
        """Compute one job's record (again, when a backend reported an ignored interrupt)."""
        settings = self.settings
        for attempt in range(BACKEND_INTERRUPT_RETRIES + 1):
            try:
                if settings.replay and cfg.path not in self.canonical:
                    self.canonical[cfg.path] = canonical_steps(cfg, settings)
                rec = self.job(cfg, solver, settings, self.canonical.get(cfg.path))
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
                self.say(f"{cfg.name} / {solver}: {err}; running the job again")
                continue
            raise_if_interrupted()  # an interrupt that was swallowed on the way still counts
            rec.update(key=key, settings=settings.as_dict(), machine=self.machine,
                       code=code_digest())
            return rec
        raise AssertionError("unreachable")  # pragma: no cover


def _line(rec: dict[str, Any]) -> str:
    """One line on a finished job for the log."""
    if rec.get("not_applicable"):
        return f"{rec['experiment']} / {rec['solver']}: not applicable: {rec['not_applicable']}"
    reason = job_failure(rec)
    if reason is not None:
        return f"{rec['experiment']} / {rec['solver']}: FAILED: {reason}"
    return (f"{rec['experiment']} / {rec['solver']}: success {rec['success_rate']:.3f}, "
            f"step median {rec['step_time_median_s'] * 1e6:.0f} us")


__all__ = ["BACKEND_INTERRUPT_RETRIES", "CANONICAL_SOLVER", "RECORD_FORMAT", "RESULTS_FILE",
           "STATUSES", "BackendInterrupted", "BenchConfig", "BenchInterrupted", "BenchResult",
           "BenchSettings", "backend_interrupted", "canonical_steps", "check_solvers",
           "code_digest", "job_failure", "machine_info", "read_config", "replay", "run_bench",
           "run_job", "settings_hash"]
