"""osqp: an ADMM method, kept as one native solver object across steps.

Each step of a rollout has the same shape (12 x 13 for the PUMA pair) and the same
sparsity, so one ``osqp.OSQP`` object is set up once and then only updated with the new
data; a new setup is done when the shape changes or the previous call failed. Every
call keeps the profile's iteration and time limit. With a full cost the call goes
through qpsolvers instead (:mod:`.qpsolvers_`).

An osqp call that a SIGINT interrupted returns no ``x``, and the signal is raised again
in Python (:func:`~dualarm_qp._signals.pass_on_sigint`): osqp's own handler swallows it
during the solve.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..._remade import KernelHolder
from ..._signals import pass_on_sigint
from ...step.problem import StepProblem
from .answer import BackendAnswer
from .base import TIME_LIMIT_S, Backend, OptionType, options_from_attributes
from .shifted import cost_weights

FloatArray = NDArray[np.float64]


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
        """Solve ``problem`` on the kept solver (updated, or set up anew for a new shape)."""
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
        y = None if x_out is None or interrupted else np.array(x_out, dtype=np.float64)
        answer = BackendAnswer(problem, y, bool(solved), bool(infeasible),
                               str(info.status), int(info.iter))
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


def osqp_options() -> dict[str, OptionType]:
    """Return the fields of osqp's ``OSQPSettings`` (and the two its wrapper translates)."""
    import osqp

    ext = osqp.OSQP().ext
    settings = ext.OSQPSettings()
    ext.osqp_set_default_settings(settings)
    out = options_from_attributes(settings)
    out["solver_type"] = OptionType("str", "direct", choices=("direct", "indirect"))
    out["cg_preconditioner"] = OptionType("str", "diagonal", choices=("diagonal", None))
    return out


#: osqp's Ruiz scaling is off: on 200 random steps with the raw cost it caused most
#: misses (52 -> 2). With the cost normalised, measured on 2,000 random and 1,975
#: recorded clearly feasible steps (misses random / recorded cold / recorded
#: warm-started): ``adaptive_rho_interval = 25`` and ``max_iter = 10000`` (the time
#: limit still holds): 0.25% / 0.46% / 0.1% -> 0.15% / 0.25% / 0.05%.
BACKEND = Backend("osqp", "osqp", sparse=True, warm_start=True, profile={
    "eps_abs": 1e-7, "eps_rel": 0.0, "polishing": True, "scaling": 0,
    "adaptive_rho_interval": 25, "max_iter": 10000, "time_limit": TIME_LIMIT_S},
    options=osqp_options, native=OSQPNative, native_module="osqp")


__all__ = ["BACKEND", "OSQPNative", "osqp_options"]
