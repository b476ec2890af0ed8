"""Native osqp and proxsuite solver objects kept across steps (private).

Each step of a rollout has the same shape (12 x 13 for the PUMA pair) and the same
sparsity, so one native solver object is set up once and then only updated with the new
data; a new setup is done when the shape changes or the previous call failed. Every
call keeps the profile's iteration (and, for osqp, time) limit. The QP is the shifted
one of :mod:`.qp`, ``min 1/2 y^T S y  s.t.  A y = b - A c,  lower - c <= y <= upper - c``,
with the cost divided by ``max(S)`` (:func:`cost_weights`; the minimiser is the same).

An osqp call that a SIGINT interrupted returns no ``x``, and the signal is raised again
in Python (:func:`~dualarm_qp._signals.pass_on_sigint`): osqp's own handler swallows it
during the solve.
"""

from __future__ import annotations

import importlib.util
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from .._remade import KernelHolder
from .._signals import pass_on_sigint
from ..step.problem import StepProblem

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class BackendAnswer:
    """What one backend call returned, in the shifted variable ``y = x - c``.

    Attributes
    ----------
    x : ndarray or None
        The backend's last iterate (None when it returned none).
    solved : bool
        The backend says it met its tolerances.
    infeasible : bool
        The backend says the constraints are inconsistent (primal infeasible).
    status : str
        The backend's status, as text.
    iterations : int or None
        Iterations used, where the backend reports them.
    """

    x: FloatArray | None
    solved: bool
    infeasible: bool
    status: str
    iterations: int | None = None


class NativeQP(Protocol):
    """A native backend object that solves a sequence of step QPs."""

    def solve(self, problem: StepProblem) -> BackendAnswer:
        """Update (or set up) the backend with ``problem`` and solve it."""
        ...


def cost_weights(weights: FloatArray) -> FloatArray:
    """Return the diagonal of the cost the backends see: ``S / max(S)`` (largest 1).

    Dividing the cost by a constant leaves the minimiser unchanged, and it keeps the
    first-order backends' penalties above the cost's curvature: with ``s7 = 1e9`` and
    the raw ``S``, proxqp's smallest penalty (``1 / mu_min_eq = 1e9``) no longer
    dominates the cost, and on 1,975 recorded feasible steps 349 stalled at their
    iteration limit with ``|A y - b| ~ 3``; normalised, they solve in under ten
    iterations.
    """
    top = float(weights.max())
    return weights / top if top > 0.0 else weights.copy()


def cost_matrix(weights: FloatArray) -> FloatArray:
    """Return the cost matrix the backends see: ``W / max |W|`` (diagonal or full, as given)."""
    if weights.ndim == 1:
        return np.diag(cost_weights(weights))
    top = float(np.abs(weights).max(initial=0.0))
    return weights / top if top > 0.0 else weights.copy()


def shifted_rows(problem: StepProblem) -> tuple[FloatArray, FloatArray]:
    """Return the general rows in ``y = x - c``: ``(G, h - G c)``, rows with a finite ``h`` only."""
    keep = np.isfinite(problem.h)
    G = problem.G[keep]
    return G, problem.h[keep] - G @ problem.center


def _box(problem: StepProblem) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Shifted data ``(b - A c, lower - c, upper - c)``."""
    c = problem.center
    return problem.b - problem.A @ c, problem.lower - c, problem.upper - c


class OSQPNative(KernelHolder):
    """One ``osqp.OSQP`` object: the equality rows, the identity (box), the rows ``G``.

    The general rows have an upper bound only.

    The constraint matrix is stored with a fixed, dense pattern (zeros kept as explicit
    entries), so a new ``A`` is always an update of the values, never a new setup.

    Per step, the data update and the solve go straight to the extension solver under
    osqp's Python wrapper when it exposes one (osqp 1.x: ``OSQP._solver``): the wrapper
    adds about 30 us per step (a settings lookup per bound vector, a derivative cache,
    and a namespace of every info field built after each solve) and nothing that
    changes the solve. The wrapper's clipping of the bounds to ``+-OSQP_INFTY`` is done
    here. Without such an object the public methods are used.
    """

    # The module and the solver set up at the last step: a pickle leaves them out, and
    # its copy sets a solver up anew at its first step (its rho and duals start afresh).
    _kernel_attributes = ("_osqp", "_solver", "_ext")

    def __init__(self, options: dict[str, Any]) -> None:
        self.options = dict(options)
        self._remake()
        self._shape: tuple[int, int, int] | None = None
        self._weights: FloatArray | None = None
        self._zero_y: FloatArray | None = None
        self._infty = float(self._osqp.constant("OSQP_INFTY"))
        # Per-step buffers: values of [A; I] in csc order, and the bounds of [A; I] x.
        self._ax = np.zeros((0, 0))
        self._l = np.zeros(0)
        self._u = np.zeros(0)

    def _remake(self) -> None:
        """Import osqp; no solver set up yet."""
        import osqp

        self._osqp = osqp
        self._solver: Any = None
        self._ext: Any = None

    def _fill(self, problem: StepProblem) -> None:
        """Write the shifted step data into the buffers (sized for the problem's shape)."""
        m, n = problem.A.shape
        p = problem.p
        if self._ax.shape != (n, m + 1 + p):
            # column j of [A; I; G]: A[:, j], then the 1, then G[:, j]
            self._ax = np.ones((n, m + 1 + p))
            self._l, self._u = np.empty(m + n + p), np.empty(m + n + p)
        c = problem.center
        self._ax[:, :m] = problem.A.T
        if p:
            self._ax[:, m + 1:] = problem.G.T
        beq = problem.b - problem.A @ c
        lo, up = self._l, self._u
        lo[:m] = beq
        up[:m] = beq
        np.subtract(problem.lower, c, out=lo[m:m + n])
        np.subtract(problem.upper, c, out=up[m:m + n])
        if p:
            lo[m + n:] = -np.inf
            with np.errstate(invalid="ignore"):
                up[m + n:] = problem.h - problem.G @ c
        np.maximum(lo, -self._infty, out=lo)
        np.minimum(up, self._infty, out=up)

    def solve(self, problem: StepProblem) -> BackendAnswer:
        import scipy.sparse as sp

        m, n = problem.A.shape
        p = problem.p
        self._fill(problem)
        ax = self._ax.ravel()
        if self._solver is None or self._shape != (m, n, p):
            # Pattern: every entry of A, the diagonal of I and every entry of G; in csc
            # order column j holds A[:, j], I[j, j], G[:, j]: the order of ``ax``.
            mat = sp.csc_matrix(np.vstack([np.ones((m, n)), np.eye(n), np.ones((p, n))]))
            mat.sort_indices()
            mat.data = ax.copy()
            solver = self._osqp.OSQP()
            solver.setup(P=sp.diags(cost_weights(problem.weights), format="csc"),
                         q=np.zeros(n), A=mat,
                         l=self._l.copy(), u=self._u.copy(), verbose=False, **self.options)
            self._solver, self._shape = solver, (m, n, p)
            self._ext = _osqp_extension(solver)
            self._weights = problem.weights.copy()
            self._zero_y = np.zeros(m + n + p)
        else:
            px = None
            if self._weights is None or not np.array_equal(self._weights, problem.weights):
                px = cost_weights(problem.weights)
                self._weights = problem.weights.copy()
            if self._ext is not None:
                self._ext.update_data_vec(q=None, l=self._l, u=self._u)
                self._ext.update_data_mat(P_x=px, P_i=None, A_x=ax, A_i=None)
            else:
                upd: dict[str, Any] = {"Ax": ax.copy(), "l": self._l.copy(),
                                       "u": self._u.copy()}
                if px is not None:
                    upd["Px"] = px
                self._solver.update(**upd)
        if problem.x_prev is not None:
            self._solver.warm_start(x=problem.x_prev - problem.center)
        else:  # no neighbouring step: a cold start
            self._solver.warm_start(x=np.zeros(n), y=self._zero_y)
        if self._ext is not None:
            self._ext.solve()
            info = self._ext.info
            x_out = self._ext.solution.x
        else:
            res = self._solver.solve(raise_error=False)
            info, x_out = res.info, res.x
        st = self._osqp.SolverStatus
        status = info.status_val
        solved = status == st.OSQP_SOLVED
        infeasible = status in (st.OSQP_PRIMAL_INFEASIBLE, st.OSQP_PRIMAL_INFEASIBLE_INACCURATE)
        interrupted = status == st.OSQP_SIGINT
        x = None if x_out is None or interrupted else np.array(x_out, dtype=np.float64)
        answer = BackendAnswer(x, bool(solved), bool(infeasible), str(info.status),
                               int(info.iter))
        if not solved:
            self._solver = None  # a failed state is not a good warm start: set up anew
            self._ext = None
        if interrupted:  # osqp caught the user's Ctrl-C: never an answer, pass it on
            pass_on_sigint()
        return answer


def _osqp_extension(solver: Any) -> Any:
    """Return the extension solver under an ``osqp.OSQP`` wrapper, or None if it has none."""
    ext = getattr(solver, "_solver", None)
    needed = ("update_data_vec", "update_data_mat", "solve", "info", "solution")
    return ext if ext is not None and all(hasattr(ext, k) for k in needed) else None


class ProxQPNative(KernelHolder):
    """One ``proxsuite.proxqp.dense.QP`` with native box constraints and general rows.

    proxqp has no time limit. Its ``max_iter`` bounds the outer (augmented Lagrangian)
    iterations only; each may run up to ``max_iter_in`` inner Newton iterations (1500 by
    default), so one call could take ``1000 * 1500`` iterations (1.6-13.6 s seen). The
    profile caps both (:data:`.qp.BACKENDS`); ``safe_guard`` is not exposed in Python.
    """

    #: Options passed to ``init`` rather than set on ``settings``.
    INIT_ONLY = ("compute_preconditioner",)

    # The module and the problem set up at the last step: a pickle leaves them out, and
    # its copy sets one up anew at its first step.
    _kernel_attributes = ("_proxqp", "_qp")

    def __init__(self, options: dict[str, Any]) -> None:
        self.options = dict(options)
        self._remake()
        self._shape: tuple[int, int, int] | None = None
        self._weights: FloatArray | None = None

    def _remake(self) -> None:
        """Import proxqp; no problem set up yet."""
        from proxsuite import proxqp

        self._proxqp = proxqp
        self._qp: Any = None

    def _rows(self, problem: StepProblem) -> tuple[Any, Any, Any]:
        """``(C, l, u)`` of the general rows in ``y`` (None without rows)."""
        if not problem.p:
            return None, None, None
        with np.errstate(invalid="ignore"):
            u = np.minimum(problem.h - problem.G @ problem.center, _PROXQP_INFTY)
        return problem.G, np.full(problem.p, -_PROXQP_INFTY), u

    def _setup(self, problem: StepProblem, beq: FloatArray, lo: FloatArray,
               up: FloatArray) -> None:
        m, n = problem.A.shape
        qp = self._proxqp.dense.QP(n, m, problem.p, True)
        for key, value in self.options.items():
            if key not in self.INIT_ONLY:
                setattr(qp.settings, key, value)
        qp.settings.verbose = False
        C, cl, cu = self._rows(problem)
        qp.init(cost_matrix(problem.weights), np.zeros(n), problem.A, beq,
                C, cl, cu,
                lo, up, compute_preconditioner=bool(
                    self.options.get("compute_preconditioner", True)))
        self._qp, self._shape = qp, (m, n, problem.p)
        self._weights = problem.weights.copy()

    def solve(self, problem: StepProblem) -> BackendAnswer:
        beq, lo, up = _box(problem)
        m, n = problem.A.shape
        if self._qp is None or self._shape != (m, n, problem.p):
            self._setup(problem, beq, lo, up)
        else:
            H = None
            if self._weights is None or not np.array_equal(self._weights, problem.weights):
                H = cost_matrix(problem.weights)
                self._weights = problem.weights.copy()
            C, cl, cu = self._rows(problem)
            self._qp.update(H, None, problem.A, beq, C, cl, cu, lo, up,
                            update_preconditioner=bool(
                                self.options.get("compute_preconditioner", True)))
        guess = self._proxqp.InitialGuess
        if problem.x_prev is not None:
            self._qp.settings.initial_guess = guess.WARM_START
            self._qp.solve(problem.x_prev - problem.center, None, None)
        else:
            self._qp.settings.initial_guess = guess.NO_INITIAL_GUESS
            self._qp.solve()
        info = self._qp.results.info
        out = self._proxqp.QPSolverOutput
        solved = info.status == out.PROXQP_SOLVED
        infeasible = info.status == out.PROXQP_PRIMAL_INFEASIBLE
        x = np.array(self._qp.results.x, dtype=np.float64)
        if not solved:
            self._qp = None
        return BackendAnswer(x, bool(solved), bool(infeasible), str(info.status),
                             int(info.iter))


#: What stands for "no bound" in proxqp's row bounds.
_PROXQP_INFTY = 1e20

#: qpsolvers backend name -> native class, for the installed backends that have one.
NATIVE: dict[str, type[OSQPNative] | type[ProxQPNative]] = {
    name: cls for name, module, cls in (("osqp", "osqp", OSQPNative),
                                        ("proxqp", "proxsuite", ProxQPNative))
    if importlib.util.find_spec(module) is not None
}
