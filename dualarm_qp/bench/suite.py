"""Score solvers on a file of recorded step problems, the way qpbenchmark scores QP solvers.

Every solver solves every instance, bare (no infeasible-step policy), in the file's
order (so warm starts come from the neighbouring recorded step). An instance counts as
**solved** only when

* the instance is feasible, the solver's status says usable, AND its residuals are
  within the tolerance profile (equality residual scaled by ``max(1, |b|_inf)``, bound
  violation, and objective at most ``objective`` (relative) above the known optimum); or
* the instance is infeasible and the solver says INFEASIBLE.

Reported per solver: the success rate, how often a claimed success (a usable status)
was true (a FEASIBLE claim, which does not claim optimality, is true when its residuals
are within the profile), and the shifted geometric mean of the solve time relative to
the best solver, with shift 10 us and an unsolved instance counted at the time limit
(as qpbenchmark).
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidInputError
from ..solvers.base import Status
from ..solvers.certify import residuals
from ..solvers.registry import get_solver
from ..step.problem import StepProblem
from .table import render_table

FloatArray = NDArray[np.float64]

#: Shift of the shifted geometric mean [s] (qpbenchmark's 10 us).
SGM_SHIFT = 1e-5

#: Time charged to an unsolved instance [s] in the shifted geometric mean: a scoring
#: convention (qpbenchmark charges its time limit). It is kept at 0.1 s, ten thousand
#: times a typical step, so that the scores stay comparable across runs; the backends'
#: own guard (qp.TIME_LIMIT_S, 1 s) is a different thing: a bound on a runaway call.
TIME_LIMIT = 0.1


@dataclass(frozen=True)
class ToleranceProfile:
    """What a solved instance must meet.

    Parameters
    ----------
    name : str
        Profile name.
    equality : float
        Largest ``|A x - b|`` component, scaled by ``max(1, |b|_inf)``.
    bounds : float
        Largest bound violation.
    objective : float
        Largest ``(f(x) - f*) / max(1, |f*|)``.
    """

    name: str
    equality: float
    bounds: float
    objective: float


PROFILES: dict[str, ToleranceProfile] = {
    "default": ToleranceProfile("default", 1e-7, 1e-7, 1e-6),
    "high_accuracy": ToleranceProfile("high_accuracy", 1e-9, 1e-9, 1e-9),
    "low_accuracy": ToleranceProfile("low_accuracy", 1e-5, 1e-5, 1e-4),
}


@dataclass(frozen=True)
class Suite:
    """Step instances with their known answers.

    Attributes
    ----------
    problems : list of StepProblem
        The instances (with ``x_prev`` for warm starts where recorded).
    feasible : ndarray of bool
        Whether each instance has a point meeting the equality and the bounds.
    objective_star : ndarray
        Optimal objective of each feasible instance (NaN for infeasible ones).
    kind : ndarray of str
        How each instance was made (``"rollout"``, ``"scaled"``, ``"pinched"``, ...).
    meta : dict
        What the generator recorded (seed, scenarios, ...).
    """

    problems: list[StepProblem]
    feasible: NDArray[np.bool_]
    objective_star: FloatArray
    kind: NDArray[np.str_]
    meta: dict[str, Any]

    def __len__(self) -> int:
        return len(self.problems)

    def subset(self, index: Sequence[int] | NDArray[np.int_]) -> Suite:
        """Return the instances at ``index``, in that order."""
        idx = np.asarray(index, dtype=int)
        return Suite([self.problems[i] for i in idx], self.feasible[idx],
                     self.objective_star[idx], self.kind[idx], self.meta)


def save_suite(path: str | Path, problems: Sequence[StepProblem], feasible: Sequence[bool],
               objective_star: Sequence[float], kind: Sequence[str],
               meta: dict[str, Any]) -> None:
    """Write a suite as a compressed ``.npz`` (no pickled objects)."""
    n = len(problems)
    if not n:
        raise InvalidInputError("an empty suite")
    shapes = {p.A.shape for p in problems}
    if len(shapes) != 1:
        raise InvalidInputError(f"every instance must have the same shape, got {shapes}")
    xp = np.full((n, problems[0].n), np.nan)
    for i, p in enumerate(problems):
        if p.x_prev is not None:
            xp[i] = p.x_prev
    np.savez_compressed(
        Path(path),
        A=np.stack([p.A for p in problems]), b=np.stack([p.b for p in problems]),
        weights=np.stack([p.weights for p in problems]),
        center=np.stack([p.center for p in problems]),
        lower=np.stack([p.lower for p in problems]),
        upper=np.stack([p.upper for p in problems]),
        x_prev=xp, n_grasp=np.array([p.n_grasp for p in problems]),
        feasible=np.asarray(feasible, dtype=bool),
        objective_star=np.asarray(objective_star, dtype=float),
        kind=np.asarray(kind, dtype=str), meta=np.array(json.dumps(meta)),
    )


def load_suite(path: str | Path) -> Suite:
    """Read a suite written by :func:`save_suite`."""
    with np.load(Path(path), allow_pickle=False) as z:
        d = {k: z[k] for k in z.files}
    problems = []
    for i in range(d["A"].shape[0]):
        xp = d["x_prev"][i]
        problems.append(StepProblem(
            A=d["A"][i], b=d["b"][i], weights=d["weights"][i], center=d["center"][i],
            lower=d["lower"][i], upper=d["upper"][i], n_grasp=int(d["n_grasp"][i]),
            x_prev=None if np.isnan(xp).any() else xp))
    return Suite(problems, d["feasible"].astype(bool), d["objective_star"].astype(float),
                 d["kind"].astype(str), json.loads(str(d["meta"])))


def is_solved(problem: StepProblem, feasible: bool, objective_star: float, status: Status,
              x: FloatArray, profile: ToleranceProfile) -> bool:
    """Whether a solver's answer to one instance is right (see the module docstring)."""
    if not feasible:
        return status is Status.INFEASIBLE
    if not status.usable or not np.isfinite(x).all():
        return False
    eq, viol = residuals(problem, x)
    b_scale = max(1.0, float(np.abs(problem.b).max(initial=0.0)))
    if eq > profile.equality * b_scale or viol > profile.bounds:
        return False
    f = problem.objective(x)
    return f - objective_star <= profile.objective * max(1.0, abs(objective_star))


def claim_is_true(problem: StepProblem, feasible: bool, objective_star: float,
                  status: Status, x: FloatArray, profile: ToleranceProfile) -> bool:
    """Whether what a usable status claims about ``x`` holds.

    OPTIMAL, SCALED, RELAXED and RECOVERING claim the answer of :func:`is_solved`;
    FEASIBLE claims only that the equality and the bounds hold.
    """
    if status is not Status.FEASIBLE:
        return is_solved(problem, feasible, objective_star, status, x, profile)
    if not feasible or not np.isfinite(x).all():
        return False
    eq, viol = residuals(problem, x)
    b_scale = max(1.0, float(np.abs(problem.b).max(initial=0.0)))
    return eq <= profile.equality * b_scale and viol <= profile.bounds


def shifted_geometric_mean(times: Sequence[float] | FloatArray,
                           shift: float = SGM_SHIFT) -> float:
    """``exp(mean(log(t + shift))) - shift`` [s]."""
    t = np.asarray(times, dtype=float)
    if not t.size:
        return float("nan")
    return float(np.exp(np.mean(np.log(t + shift))) - shift)


@dataclass
class SolverRun:
    """Raw outcome of one solver over a suite (one entry per instance)."""

    solver: str
    status: list[str]
    claimed: NDArray[np.bool_]
    time_s: FloatArray
    solutions: FloatArray


def run_solver(suite: Suite, solver: str, *, options: dict[str, Any] | None = None,
               progress: Callable[[int, int], None] | None = None) -> SolverRun:
    """Solve every instance of ``suite`` with a fresh ``solver``, timing each call."""
    s = get_solver(solver, **(options or {}))
    n = len(suite)
    status: list[str] = []
    claimed = np.zeros(n, dtype=bool)
    times = np.zeros(n)
    xs = np.full((n, suite.problems[0].n if n else 0), np.nan)
    for i, p in enumerate(suite.problems):
        t0 = time.perf_counter()
        sol = s.solve(p)
        times[i] = time.perf_counter() - t0
        status.append(sol.status.value)
        claimed[i] = sol.status.usable
        xs[i] = sol.x
        if progress is not None:
            progress(i + 1, n)
    return SolverRun(solver, status, claimed, times, xs)


def score(suite: Suite, runs: Sequence[SolverRun], profile: ToleranceProfile,
          *, time_limit: float = TIME_LIMIT) -> list[dict[str, Any]]:
    """One row per solver: success rate, true-claim rate, relative shifted geo. mean."""
    rows: list[dict[str, Any]] = []
    sgms: dict[str, float] = {}
    for run in runs:
        solved = np.array([
            is_solved(p, bool(f), float(o), Status(st), x, profile)
            for p, f, o, st, x in zip(suite.problems, suite.feasible, suite.objective_star,
                                      run.status, run.solutions, strict=True)])
        charged = np.where(solved, run.time_s, max(time_limit, 0.0))
        sgms[run.solver] = shifted_geometric_mean(charged)
        n_claim = int(run.claimed.sum())
        true_claims = sum(
            claim_is_true(p, bool(f), float(o), Status(st), x, profile)
            for p, f, o, st, x, c in zip(suite.problems, suite.feasible, suite.objective_star,
                                         run.status, run.solutions, run.claimed, strict=True)
            if c)
        feas = suite.feasible
        rows.append({
            "solver": run.solver,
            "profile": profile.name,
            "instances": len(suite),
            "solved": int(solved.sum()),
            "success_rate": float(solved.mean()) if len(suite) else float("nan"),
            "success_rate_feasible": float(solved[feas].mean()) if feas.any() else math.nan,
            "infeasible_detected": float(solved[~feas].mean()) if (~feas).any() else math.nan,
            "claimed": n_claim,
            "claimed_true_rate": true_claims / n_claim if n_claim else float("nan"),
            "time_median_s": float(np.median(run.time_s)) if run.time_s.size else math.nan,
            "time_p99_s": float(np.percentile(run.time_s, 99)) if run.time_s.size
            else math.nan,
            "sgm_time_s": sgms[run.solver],
        })
    best = min((v for v in sgms.values() if math.isfinite(v)), default=float("nan"))
    for row in rows:
        row["sgm_time_rel"] = sgms[row["solver"]] / best if best > 0 else float("nan")
    return rows


SUITE_TABLE: tuple[tuple[str, str, str], ...] = (
    ("solver", "solver", "{}"),
    ("success", "success_rate", "{:.3f}"),
    ("feasible solved", "success_rate_feasible", "{:.3f}"),
    ("infeasible detected", "infeasible_detected", "{:.3f}"),
    ("claims true", "claimed_true_rate", "{:.3f}"),
    ("time median us", "time_median_s", "us"),
    ("time p99 us", "time_p99_s", "us"),
    ("sgm rel", "sgm_time_rel", "{:.2f}"),
)


def format_suite_table(rows: Sequence[dict[str, Any]], *, markdown: bool = False) -> str:
    """Format the scored rows as a text (or Markdown) table."""
    cells = [[h for h, _, _ in SUITE_TABLE]]
    for r in rows:
        line = []
        for _, col, fmt in SUITE_TABLE:
            v = r.get(col)
            if isinstance(v, float) and not math.isfinite(v):
                line.append("-")
            elif fmt == "us":
                line.append(f"{float(v) * 1e6:.1f}")  # type: ignore[arg-type]
            else:
                line.append(fmt.format(v))
        cells.append(line)
    return render_table(cells, markdown=markdown, left_columns=1)
