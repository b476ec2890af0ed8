"""The per-step controller: measured state in, both arms' rates and sliding speeds out.

The controller stands on its own so that it can be dropped into a real control loop:
call :meth:`DualArmController.step` once per sample with the measured joints of both
arms, the grasp coordinate and the path time; apply ``ql_dot`` to the leader,
``qf_dot`` to the follower and let the grasp slide at ``m``.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from ..errors import (
    DualArmError,
    InfeasibleStepError,
    InvalidInputError,
    NonFiniteError,
    ShapeError,
)
from ..solvers.base import DEFAULT_TOLERANCE, Status, StepSolution, StepSolver, Tolerance
from ..solvers.certify import certify, equality_limit
from ..solvers.policy import POLICIES, Policy, solve_step
from ..solvers.registry import certified, check_pairing
from ..step.build import StepBuild, StepBuilder
from ..step.layout import Layout
from ..step.options import StepOptions
from ..step.parts import CostTerm, Limit, Task
from ..step.problem import StepProblem
from ..step.state import DualArmState
from ..task.scene import DualArmTask
from .diagnosis import explain
from .escape import COLLAPSED_SCALE, escape_move
from .lookahead import Lookahead
from .output import ControlOutput, StepTimes

#: How many times a step over its error budget may halve its task scale.
BUDGET_HALVINGS = 6

#: Position error [m] an escape move off the null space may cost per step without an
#: error budget: a quarter of it (the default tolerance is 1 mm).
DEFAULT_ESCAPE_BUDGET = 0.5e-3

FloatArray = NDArray[np.float64]


class DualArmController:
    """One step problem for both arms and every sliding grasp, within every limit.

    Each step builds one problem (:mod:`dualarm_qp.step.build`) whose decision vector
    holds both arms' joint rates and every sliding speed: the object follows ``D(t)``
    (the leader's task) and the follower's tool stays on its grasp (the closure), each
    variable inside its range and speed limit when the solver claims hard limits, at
    the Eq. 37 optimum. With a six-joint leader that grasps rigidly this is the paper's
    leader step followed by its 7-dof follower step (Eqs. 25-40). An infeasible step
    goes through the policy once: under ``"scale"`` the largest feasible task scale
    slows the path for both arms together.

    Parameters
    ----------
    task : DualArmTask
        Arms, object, surfaces and desired path.
    solver : StepSolver
        Any solver from the registry (``dualarm_qp.solvers.get_solver``).
    options : StepOptions
        Step-problem settings (dt, weights, limits, correction gain).
    leader_gain : float, optional
        Feedback gain [1/s] of the object's tracking of ``D(t)``; default
        ``options.leader_gain`` (``1/dt`` unless set).
    policy : {"scale", "relax", "stop"}
        What to do with an infeasible step (see :func:`dualarm_qp.solvers.solve_step`).
    tolerance : Tolerance
        What counts as meeting the equality and the bounds.
    fallback : StepSolver, optional
        Solver for a step on which ``solver`` fails although the step is feasible (the
        exact ``nullspace`` solver is the usual choice); None lets such a step fail.
    on_step : callable, optional
        Called with every :class:`ControlOutput` before :meth:`step` returns it (to
        record the step problems, or to refuse an answer by raising); what it raises
        leaves :meth:`step`.
    error_budget : tuple of float, optional
        ``(position [m], rotation [rad])``: the largest leader tracking and grasp closure
        error one step may leave at the next sample, predicted by forward kinematics
        (:mod:`.lookahead`). A step predicted over it is slowed through the task scale,
        as the limits slow it (halving the scale up to :data:`BUDGET_HALVINGS` times);
        its status is then SCALED. None (the default) predicts nothing. Only for a
        solver that claims hard limits (the paper's methods take their steps as given).
    singularity_escape : float, optional
        Smallest singular value [mixed units, as ``sigma_min``] below which an arm at a
        step whose task scale collapsed takes an escape move (:mod:`.escape`, status
        ESCAPING); default 1e-3. None never escapes. Only for a solver that claims
        hard limits.
    limits : sequence of Limit
        Limits of the user's, asked after the standard ones
        (:mod:`dualarm_qp.step.parts`; ``examples/custom_limit.py``). A limit that gives
        rows needs a solver that takes rows (:class:`~dualarm_qp.errors.PairingError`
        otherwise).
    tasks : sequence of Task
        Tasks of the user's, asked after the standard ones: equality rows, or with a
        ``weight`` a term of the cost (``examples/custom_task.py``). A weighted task
        makes the cost a full matrix: a solver that takes a diagonal cost only refuses
        it.
    costs : sequence of CostTerm
        Cost terms of the user's, summed with the paper's centring.

    Raises
    ------
    InvalidInputError
        An unknown policy, a malformed budget, escape threshold or limit.
    PairingError
        A limit gives rows and the solver takes boxes only (the message names the solver,
        the limit and the solvers that can take it).

    Notes
    -----
    The paper's methods (``reference``, ``fixed_grasp``) ignore limits by design; for
    them the leader's box is left open too.
    """

    def __init__(
        self,
        task: DualArmTask,
        solver: StepSolver,
        options: StepOptions,
        *,
        leader_gain: float | None = None,
        policy: Policy = "scale",
        tolerance: Tolerance = DEFAULT_TOLERANCE,
        fallback: StepSolver | None = None,
        on_step: Callable[[ControlOutput], None] | None = None,
        error_budget: tuple[float, float] | None = None,
        singularity_escape: float | None = 1e-3,
        limits: Sequence[Limit] = (),
        tasks: Sequence[Task] = (),
        costs: Sequence[CostTerm] = (),
    ) -> None:
        if policy not in POLICIES:
            raise InvalidInputError(f"policy must be one of {POLICIES}, got {policy!r}")
        self.task = task
        # Every answer is certified once, with the controller's tolerances.
        self.solver = certified(solver, tolerance)
        self.options = options
        self.policy = policy
        self.tolerance = tolerance
        self.fallback = None if fallback is None else certified(fallback, tolerance)
        self.on_step = on_step
        self._hard_bounds = self.solver.info.hard_bounds
        self._builder = StepBuilder(task, options, leader_bounds=self._hard_bounds,
                                    limits=limits, tasks=tasks, costs=costs)
        check_pairing(self.solver.info, self._builder.row_limits, self._builder.full_cost)
        if leader_gain is not None:  # else the builder's, from the options
            self.leader_gain = leader_gain
        self._x_prev: FloatArray | None = None
        self._x_applied = np.zeros(self._builder.n)
        self._x_applied_prev = self._x_applied  # the one before it (jerk limits)
        self._lookahead: Lookahead | None = None
        if error_budget is not None and self._hard_bounds:
            if not (len(error_budget) == 2 and all(
                    math.isfinite(v) and v > 0 for v in error_budget)):
                raise InvalidInputError(f"error_budget must be two positive numbers (m, rad), "
                                        f"got {error_budget!r}")
            b = self._builder
            self._lookahead = Lookahead(task, error_budget, b.carry, b.n_l, b.n_f)
        if singularity_escape is not None and not (math.isfinite(singularity_escape)
                                                   and singularity_escape > 0):
            raise InvalidInputError("singularity_escape must be a positive number or None, "
                                    f"got {singularity_escape!r}")
        self._escape = singularity_escape if self._hard_bounds else None

    @property
    def leader_gain(self) -> float:
        """Feedback gain [1/s] of the object's tracking of ``D(t)``."""
        return self._builder.leader_gain

    @leader_gain.setter
    def leader_gain(self, value: float) -> None:
        if not (np.isfinite(value) and value >= 0):
            raise InvalidInputError("leader_gain must be a finite number >= 0 [1/s]")
        self._builder.leader_gain = float(value)

    @property
    def hard_bounds(self) -> bool:
        """Whether the solver claims hard limits (False for the paper's methods)."""
        return self._hard_bounds

    @property
    def names(self) -> tuple[str, ...]:
        """Names of the decision variables: ``ql1.., qf1.., m`` and ``m_l`` if it slides."""
        return self._builder.names

    @property
    def layout(self) -> Layout:
        """The slices of the decision vector."""
        return self._builder.layout

    @property
    def builder(self) -> StepBuilder:
        """The step builder: its tasks, cost and limits (``.limits``), and ``build``."""
        return self._builder

    @property
    def applied(self) -> FloatArray:
        """The last command applied [rad/s, m/s] (what acceleration limits start from)."""
        return self._x_applied.copy()

    def explain(self, state: DualArmState) -> str:
        """Why the task cannot be followed at ``state`` (:func:`.diagnosis.explain`).

        With an error budget, the step at full path speed is solved and its predicted
        errors at the next sample are weighed against the budget too.
        """
        la = self._lookahead
        share = None
        if la is not None:
            build = self._builder.build(state)
            state = build.context.state
            problem = build.problem
            try:
                sol = solve_step(self.solver, problem, policy="scale", tol=self.tolerance,
                                 fallback=self.fallback)
            except DualArmError:
                sol = None
            if sol is not None and sol.status.usable:
                share = la.predict_checked(state, _inside(sol.x, problem), sol.scale,
                                           self.options.dt).share(la.budget)
        return explain(self._builder, state, budget_share=share,
                       budget=None if la is None else la.budget)

    def reset(self, rates: FloatArray | None = None) -> None:
        """Forget the warm start and set the last applied command (call between runs).

        Parameters
        ----------
        rates : ndarray, shape (n,), optional
            The rates the pair already moves at [rad/s, m/s], in the decision order
            (:attr:`layout`); default zero (the run starts at rest).
        """
        self._x_prev = None
        n = self._builder.n
        if rates is None:
            self._x_applied = self._x_applied_prev = np.zeros(n)
        else:
            x = np.asarray(rates, dtype=np.float64)
            if x.shape != (n,):
                raise ShapeError("rates", (n,), x.shape)
            if not np.isfinite(x).all():
                raise NonFiniteError("rates")
            self._x_applied = self._x_applied_prev = x.copy()  # moving at constant rates

    def step(self, state: DualArmState, *, scale_max: float = 1.0) -> ControlOutput:
        """Compute one step's command from the measured ``state``.

        The step, in order: the builder's one loop (the context, every task, cost term
        and limit asked in turn, their pieces stacked: :meth:`StepBuilder.build`), the
        solve under the policy (every answer certified once), the guards (the
        look-ahead's error budget, the escape from a singularity), the command applied.

        Parameters
        ----------
        state : DualArmState
            Measured joints of both arms, grasp coordinates and path time.
        scale_max : float
            Largest path-time rate of this step in [0, 1]: the path's feed-forward is
            scaled by it (a rollout passes less than 1 when the path ends within the
            sample).

        Never raises for an infeasible step under the "scale" and "relax" policies:
        the status says what happened. Under "stop" an infeasible step raises
        :class:`~dualarm_qp.errors.InfeasibleStepError` naming the conflicting bounds
        (``ql<i>``, ``qf<i>``, ``m``), with both arms' smallest singular values.

        Raises
        ------
        ShapeError, NonFiniteError, InvalidInputError
            A joint vector of the wrong length or with NaN, a non-finite grasp or time,
            ``scale_max`` outside [0, 1].
        """
        if not 0.0 <= scale_max <= 1.0:
            raise InvalidInputError(f"scale_max must be in [0, 1], got {scale_max}")
        build = self._builder.build(state, scale_max=scale_max, x_prev=self._x_prev,
                                    x_applied=self._x_applied,
                                    x_applied_prev=self._x_applied_prev)
        solved = time.perf_counter()
        solution = self._solved(build)
        guarded = time.perf_counter()
        solution, command = self._guarded(build, solution, scale_max)
        out = self._applied(build, solution, command, scale_max, StepTimes(
            build.kinematics_time, build.assembly_time, guarded - solved,
            time.perf_counter() - guarded))
        if self.on_step is not None:
            self.on_step(out)
        return out

    def _solved(self, build: StepBuild) -> StepSolution:
        """Solve the step under the policy (every answer certified once)."""
        try:
            return solve_step(self.solver, build.problem, policy=self.policy,
                              tol=self.tolerance, fallback=self.fallback)
        except InfeasibleStepError as err:
            sv_l, sv_f = build.sigma_min
            raise InfeasibleStepError(
                f"{err.reason} (smallest singular values of the arms' Jacobians: leader "
                f"{sv_l:.3g}, follower {sv_f:.3g})", conflicts=err.conflicts) from None

    def _guarded(self, build: StepBuild, solution: StepSolution, scale_max: float
                 ) -> tuple[StepSolution, FloatArray]:
        """Keep the answer within the error budget, or escape a collapsed step.

        Returns the answer and its command: its ``x`` clipped to the box when the solver
        claims hard limits (:func:`_inside`), else its ``x``.
        """
        problem = build.problem
        command = _inside(solution.x, problem) if self._hard_bounds else solution.x
        la = self._lookahead
        if la is not None and solution.status.usable and solution.scale > 0.0 \
                and scale_max > 0.0:
            solution, command = self._within_budget(la, build, solution, command, scale_max)
        if (self._escape is not None and solution.status is Status.SCALED
                and solution.scale < COLLAPSED_SCALE
                and min(build.sigma_min) < self._escape):
            escaped = self._escaped(build, solution, command, self._escape)
            if escaped is not solution:
                solution, command = escaped, _inside(escaped.x, problem)
        return solution, command

    def _applied(self, build: StepBuild, solution: StepSolution, command: FloatArray,
                 scale_max: float, times: StepTimes) -> ControlOutput:
        """Return ``command``, the rates of ``solution`` (:meth:`_guarded`), as applied."""
        problem = build.problem
        status = solution.status
        if (status is Status.OPTIMAL or status is Status.FEASIBLE) and build.recovers:
            status = Status.RECOVERING
            solution = replace(solution, status=status)
        if not self._hard_bounds and status is Status.VIOLATION:
            # The paper's methods ignore the bounds by design: integrate a bound
            # violation and report it, but never a step whose equality is broken.
            usable_x = solution.eq_residual <= equality_limit(problem, self.tolerance)
        else:
            usable_x = status.usable
        x = command if usable_x else np.zeros(problem.n)
        self._x_prev = x if usable_x else None
        if usable_x:
            self._x_applied_prev, self._x_applied = self._x_applied, x
        scale = scale_max * min(max(solution.scale, 0.0), 1.0) if usable_x else 0.0
        ql_dot, qf_dot, m, m_leader = self._builder.layout.split(x)
        return ControlOutput(ql_dot=ql_dot, qf_dot=qf_dot, m=m, m_leader=m_leader,
                             scale=scale, status=status, solution=solution, build=build,
                             times=times, applied=usable_x)

    def _within_budget(self, la: Lookahead, build: StepBuild, solution: StepSolution,
                       command: FloatArray, scale_max: float
                       ) -> tuple[StepSolution, FloatArray]:
        """Slow the task until the errors predicted at the next sample fit the budget.

        Returns ``solution`` and ``command`` when the prediction of its ``command`` (its
        ``x`` clipped to the box, what would be applied) fits (or is negligible by the
        bound), else the solve of the task scaled by the first halving of the scale whose
        prediction fits, or the one with the smallest prediction (status SCALED), with
        its command.
        """
        dt = self.options.dt
        problem = build.problem
        state = build.context.state
        if la.negligible(build, command, dt):
            return solution, command
        pred = la.predict_checked(state, command, scale_max * solution.scale, dt)
        share = pred.share(la.budget)
        if share <= 1.0:
            return solution, command
        best, best_command, best_share = solution, command, share
        factor = solution.scale
        for _ in range(BUDGET_HALVINGS):
            factor *= 0.5
            scaled = problem.scaled(factor)
            try:
                trial = solve_step(self.solver, scaled, policy=self.policy, tol=self.tolerance,
                                   fallback=self.fallback)
            except InfeasibleStepError:
                break
            if not trial.status.usable:
                break
            x = _inside(trial.x, scaled)
            scale = factor * trial.scale
            trial_share = la.predict_checked(state, x, scale_max * scale, dt).share(la.budget)
            if trial_share < best_share:
                best_command = x
                best, best_share = replace(
                    trial, status=Status.SCALED, scale=scale,
                    message=(f"task scaled to {scale:.6g}: at full scale the step would "
                             f"leave {share:.3g} times the error budget "
                             f"({la.budget[0]:g} m, {la.budget[1]:g} rad) at the next "
                             "sample")), trial_share
            if trial_share <= 1.0:
                break
        return best, best_command

    def _escaped(self, build: StepBuild, solution: StepSolution, command: FloatArray,
                 threshold: float) -> StepSolution:
        """Return the escape move from a collapsed ``command`` (:mod:`.escape`), or ``solution``."""
        lay = self._builder.layout
        state = build.context.state
        task = self.task
        arms = tuple(arm for arm, sv in zip(
            (("leader", task.leader, lay.leader, state.q_l),
             ("follower", task.follower, lay.follower, state.q_f)),
            build.sigma_min, strict=True) if sv < threshold)
        problem = build.problem
        budget = (self._lookahead.budget[0] if self._lookahead is not None
                  else DEFAULT_ESCAPE_BUDGET)
        esc = escape_move(problem, command, arms, threshold,
                          self.options.dt, budget)
        if esc is None:
            return solution
        how = ("in the null space of the task" if esc.null_space else
               "off the task's null space, within a quarter of the error budget")
        return certify(problem.scaled(solution.scale), replace(
            solution, x=esc.x, status=Status.ESCAPING,
            message=(f"escaping the singularity of the {' and '.join(esc.arms)} (smallest "
                     f"singular values {build.sigma_min[0]:.3g}, {build.sigma_min[1]:.3g}): "
                     f"a move {how} raising it by {esc.rate:.3g} per s; "
                     f"{solution.message}")), self.tolerance)


def _inside(x: FloatArray, problem: StepProblem) -> FloatArray:
    """``x`` clipped to the problem's box.

    A verified answer may pass a bound by up to the bound tolerance (1e-7 per s); the
    clip removes that, so that the integrated motion keeps the ranges exactly rather
    than to ``tolerance * dt``. It moves ``A x`` by at most ``|A|`` times that much.
    """
    return np.minimum(np.maximum(x, problem.lower), problem.upper)

