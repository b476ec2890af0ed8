"""Random step problems and an independent high-accuracy reference for the solver tests.

The reference enumerates active sets: on a random instance at most ``d = n - m``
bounds are active at the optimum, so it solves the KKT system of every working set of
at most ``d`` bounds (with one step of iterative refinement) and keeps the KKT point:
primal feasible with multipliers of the right sign. It shares no code with the solvers.
"""

from __future__ import annotations

import itertools

import numpy as np
from scipy.optimize import linprog

from dualarm_qp.step.problem import StepProblem


def random_problem(rng: np.random.Generator, *, n: int = 7, m: int = 6,
                   cond: float = 100.0, box: float = 1.0, s7: float | None = None,
                   n_grasp: int = 1) -> StepProblem:
    """A feasible step: ``A`` with condition ``<= cond``, ``b = A x_f`` for ``x_f`` in the box.

    The centre is perturbed away from the box centre so that some bounds are active.
    """
    U, _ = np.linalg.qr(rng.standard_normal((m, m)))
    V, _ = np.linalg.qr(rng.standard_normal((n, n)))
    sv = np.geomspace(1.0, 1.0 / cond, m)
    A = U @ np.diag(sv) @ V[:m]
    x_f = rng.uniform(-1.0, 1.0, n)
    lower = x_f - rng.uniform(0.05, box, n)
    upper = x_f + rng.uniform(0.05, box, n)
    weights = np.ones(n)
    weights[n - n_grasp:] = s7 if s7 is not None else 10.0 ** rng.uniform(2, 6)
    center = 0.5 * (lower + upper) + rng.normal(0.0, 0.6, n)
    return StepProblem(A=A, b=A @ x_f, weights=weights, center=center, lower=lower,
                       upper=upper, n_grasp=n_grasp)


def kkt_equality(problem: StepProblem) -> np.ndarray:
    """Minimiser of Eq. 37 subject to ``A x = b`` only, from its KKT system."""
    return _kkt(problem, [], [])[0]


def _kkt(problem: StepProblem, idx: list[int], val: list[float]
         ) -> tuple[np.ndarray, np.ndarray]:
    """Solve [S -A^T -E^T; A 0 0; E 0 0] [x; lam; mu] = [S c; b; val] (refined once)."""
    n, m, k = problem.n, problem.m, len(idx)
    E = np.zeros((k, n))
    E[np.arange(k), idx] = 1.0
    K = np.zeros((n + m + k, n + m + k))
    K[:n, :n] = np.diag(problem.weights)
    K[:n, n:n + m] = -problem.A.T
    K[:n, n + m:] = -E.T
    K[n:n + m, :n] = problem.A
    K[n + m:, :n] = E
    rhs = np.concatenate([problem.weights * problem.center, problem.b, np.asarray(val)])
    sol = np.linalg.solve(K, rhs)
    sol += np.linalg.solve(K, rhs - K @ sol)
    return sol[:n], sol[n + m:]


def reference_qp(problem: StepProblem, max_active: int | None = None) -> np.ndarray | None:
    """Exact minimiser of Eq. 37 with ``A x = b`` and the box, by active-set enumeration.

    Returns None when no working set of at most ``max_active`` bounds (default n - m)
    gives a KKT point (infeasible, or a degenerate instance).
    """
    n = problem.n
    d = n - problem.m if max_active is None else max_active
    best: np.ndarray | None = None
    tol = 1e-9
    for k in range(d + 1):
        for idx in itertools.combinations(range(n), k):
            for sides in itertools.product((False, True), repeat=k):
                val = [problem.upper[i] if up else problem.lower[i]
                       for i, up in zip(idx, sides, strict=True)]
                try:
                    x, mu = _kkt(problem, list(idx), val)
                except np.linalg.LinAlgError:
                    continue
                if (x < problem.lower - tol).any() or (x > problem.upper + tol).any():
                    continue
                # S (x - c) = A^T lam + mu: lower needs mu >= 0, upper mu <= 0.
                signs = np.array([-1.0 if up else 1.0 for up in sides])
                if (signs * mu < -1e-9 * max(1.0, np.abs(mu).max(initial=0.0))).any():
                    continue
                if best is None or problem.objective(x) < problem.objective(best):
                    best = x
    return best


def lp_max_scale(problem: StepProblem, cap: float = 1.0) -> float | None:
    """Largest s in [0, cap] with {A x = s b, box} non-empty (scipy HiGHS LP)."""
    n = problem.n
    cost = np.zeros(n + 1)
    cost[-1] = -1.0
    bounds = [*zip(problem.lower, problem.upper, strict=True), (0.0, cap)]
    res = linprog(cost, A_eq=np.hstack([problem.A, -problem.b[:, None]]),
                  b_eq=np.zeros(problem.m), bounds=bounds, method="highs")
    return float(res.x[-1]) if res.status == 0 else None


def relative_error(x: np.ndarray, ref: np.ndarray) -> float:
    """max |x - ref| / max(1, max |ref|)."""
    return float(np.abs(x - ref).max() / max(1.0, np.abs(ref).max()))


def with_rows(problem: StepProblem, rng: np.random.Generator, rows: int,
              tight: float = 0.3) -> StepProblem:
    """``problem`` with ``rows`` random general rows ``G x <= h`` (random normals, scaled
    by up to 3), each within ``tight`` of the unconstrained-by-rows optimum's far side so
    that some bind; every row holds at a feasible point ``x_f`` of the original problem
    (a point of the box that meets ``A x = b``), so the problem stays feasible."""
    x_f = np.linalg.lstsq(problem.A, problem.b, rcond=None)[0]
    N = np.linalg.svd(problem.A)[2][problem.m:].T
    # A feasible point: the least-squares point moved into the box along the null space.
    res = linprog(np.zeros(N.shape[1]), A_ub=np.vstack([N, -N]),
                  b_ub=np.concatenate([problem.upper - x_f, x_f - problem.lower]),
                  bounds=[(None, None)] * N.shape[1], method="highs")
    if res.status == 0:
        x_f = x_f + N @ res.x
    G = rng.standard_normal((rows, problem.n)) * rng.uniform(0.3, 3.0, (rows, 1))
    h = G @ x_f + rng.uniform(0.0, tight, rows) * np.linalg.norm(G, axis=1)
    return StepProblem(A=problem.A, b=problem.b, weights=problem.weights,
                       center=problem.center, lower=problem.lower, upper=problem.upper,
                       G=G, h=h, n_grasp=problem.n_grasp,
                       row_names=tuple(f"row{i + 1}" for i in range(rows)))


def reference_qp_rows(problem: StepProblem) -> np.ndarray | None:
    """Exact minimiser of Eq. 37 with ``A x = b``, the box and the rows ``G x <= h``, by
    enumerating active sets of boxes and rows (KKT system solved directly); None when no
    active set of at most ``n - m`` limits gives a KKT point. Shares no code with the
    library."""
    n, m = problem.n, problem.m
    C = np.vstack([np.eye(n), -np.eye(n), problem.G])
    e = np.concatenate([problem.upper, -problem.lower, problem.h])
    W = np.diag(problem.weights)
    best: np.ndarray | None = None
    for k in range(n - m + 1):
        for idx in itertools.combinations(range(C.shape[0]), k):
            Ca = C[list(idx)]
            K = np.block([[W, problem.A.T, Ca.T],
                          [problem.A, np.zeros((m, m + k))],
                          [Ca, np.zeros((k, m + k))]])
            rhs = np.concatenate([W @ problem.center, problem.b, e[list(idx)]])
            try:
                sol = np.linalg.solve(K, rhs)
            except np.linalg.LinAlgError:
                continue
            sol += np.linalg.solve(K, rhs - K @ sol)
            # A singular K that the solve did not notice gives no KKT point: its answer
            # misses the system (seen: A x - b of 0.03 with five rows active).
            if np.abs(K @ sol - rhs).max() > 1e-9 * max(1.0, float(np.abs(rhs).max())):
                continue
            x, mu = sol[:n], sol[n + m:]
            if (C @ x - e > 1e-9 * np.maximum(1.0, np.abs(e))).any():
                continue
            # W (x - c) + A^T lam + C_a^T mu = 0: an active upper limit needs mu >= 0.
            if (mu < -1e-9 * max(1.0, float(np.abs(mu).max(initial=0.0)))).any():
                continue
            if best is None or problem.objective(x) < problem.objective(best):
                best = x
    return best
