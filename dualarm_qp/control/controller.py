"""The per-step controller: measured state in, joint rates and sliding speed out.

The controller stands on its own so that it can be dropped into a real control loop:
call :meth:`DualArmController.step` once per sample with the measured joints of both
arms, the grasp coordinate and the path time; apply ``ql_dot`` to the leader,
``qf_dot`` to the follower and let the grasp slide at ``m``.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from ..errors import InfeasibleStepError, InvalidInputError, NonFiniteError, SolverNotFoundError
from ..solvers.base import (
    DEFAULT_TOLERANCE,
    Status,
    StepSolution,
    StepSolver,
    Tolerance,
    equality_limit,
    verify,
)
from ..solvers.nullspace import NullspaceSolver
from ..solvers.policy import POLICIES, Policy, solve_step
from ..solvers.registry import solver_info
from ..step.build import DualArmState, StepBuild, StepBuilder, StepOptions
from ..step.leader import LeaderBuild, LeaderStepBuilder
from ..step.problem import StepProblem
from ..task.scene import DualArmTask

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class StepTimes:
    """Wall-clock split of one controller step [s].

    ``kinematics`` holds both arms' forward kinematics, Jacobians and smallest singular
    values; ``assembly``, ``solve`` and ``verify`` the follower's problem; ``leader`` the
    leader's whole step (assembly and solve).
    """

    kinematics: float
    assembly: float
    solve: float
    verify: float
    leader: float = 0.0

    @property
    def total(self) -> float:
        """Whole controller step [s]."""
        return self.kinematics + self.assembly + self.solve + self.verify + self.leader


@dataclass(frozen=True)
class ControlOutput:
    """What one controller step commands.

    Attributes
    ----------
    ql_dot : ndarray, shape (n_l,)
        Leader joint rates [rad/s] (already scaled when the task was slowed).
    qf_dot : ndarray, shape (n_f,)
        Follower joint rates [rad/s].
    m : float
        Grasp sliding speed [m/s].
    scale : float
        Path-time rate of this step: the path advances by ``scale * dt`` (1.0 = full
        speed). The product of the ``scale_max`` asked for, the leader's task scale and
        the follower's.
    status : Status
        Follower solver status, or RECOVERING when a follower variable started outside
        its range and the solver met the bounds that pull it back; the leader's status
        when the leader's step was unusable (the follower's was then not solved).
    solution : StepSolution
        The verified follower solver output (``extras["fallback"]`` when the step was
        solved by the fallback solver after the configured one failed).
    build : StepBuild
        The follower step problem and what the builder noticed (None when the leader's
        step was unusable and the follower's was not built).
    leader : LeaderBuild
        The leader's step problem and its tracking error.
    leader_solution : StepSolution
        The leader's verified step (its ``scale`` is the leader's task scale).
    sigma_min : tuple of float
        Smallest singular value of the leader's and the follower's joint Jacobian
        (rows ``[v; w]`` in m/s and rad/s per rad/s).
    times : StepTimes
        Timing split of the step.
    applied : bool
        Whether the command is meant to be applied. True for every usable status,
        and for a bound VIOLATION of a method that ignores bounds by design (the
        paper's reference step) whose equality holds; False otherwise (the rates are
        then zero).
    """

    ql_dot: FloatArray
    qf_dot: FloatArray
    m: float
    scale: float
    status: Status
    solution: StepSolution
    build: StepBuild | None
    leader: LeaderBuild
    leader_solution: StepSolution
    sigma_min: tuple[float, float]
    times: StepTimes
    applied: bool

    @property
    def leader_error(self) -> FloatArray:
        """Leader tool pose error to its target ``D(t) H1^-1`` [m, rad]."""
        return self.leader.error

    @property
    def fallback(self) -> bool:
        """Whether the fallback solver produced this step's follower command."""
        return "fallback" in self.solution.extras


class DualArmController:
    """Leader tracking plus the redundancy-resolved follower step, both within limits.

    Each step solves two problems in turn. The leader's (:mod:`dualarm_qp.step.leader`):
    its rates that move the object along ``D(t)``, inside the leader's joint ranges and
    speed limits when the solver claims hard limits. Then the follower's (Eqs. 25-40)
    for those leader rates. Both go through the same infeasible-step policy: under
    ``"scale"`` the leader's largest feasible task scale slows the path for both arms,
    and the follower may slow it further (the leader's rates are scaled with it, which
    keeps them in their box, since a box of rates always holds 0 and scaling
    shrinks the rates towards it).

    Parameters
    ----------
    task : DualArmTask
        Arms, object, surface and desired path.
    solver : StepSolver
        Any solver from the registry (``dualarm_qp.solvers.get_solver``).
    options : StepOptions
        Step-problem settings (dt, weights, limits, correction gain).
    leader_gain : float, optional
        Feedback gain [1/s] of the leader's tracking of ``D(t)``; default ``1/dt``.
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

    Notes
    -----
    The leader's problem is square (six joints, six task rows): it has at most one
    solution, which the exact ``nullspace`` solver finds. The paper's methods
    (``reference``, ``fixed_grasp``) ignore limits by design; for them the leader's box
    is left open.
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
    ) -> None:
        if policy not in POLICIES:
            raise InvalidInputError(f"policy must be one of {POLICIES}, got {policy!r}")
        if leader_gain is None:
            leader_gain = 1.0 / options.dt
        self.task = task
        self.solver = solver
        self.options = options
        self.policy = policy
        self.tolerance = tolerance
        self.fallback = fallback
        self.on_step = on_step
        try:
            self._hard_bounds = solver_info(solver.name).hard_bounds
        except SolverNotFoundError:  # a solver not from the registry: it claims the bounds
            self._hard_bounds = True
        self._builder = StepBuilder(task, options)
        self._leader_builder = LeaderStepBuilder(task, options, 0.0, bounds=self._hard_bounds)
        self.leader_gain = leader_gain  # checked by the setter
        self._leader_solver = NullspaceSolver(tol=tolerance)
        self._x_prev: FloatArray | None = None

    @property
    def leader_gain(self) -> float:
        """Feedback gain [1/s] of the leader's tracking of ``D(t)``."""
        return self._leader_builder.gain

    @leader_gain.setter
    def leader_gain(self, value: float) -> None:
        if not (np.isfinite(value) and value >= 0):
            raise InvalidInputError("leader_gain must be a finite number >= 0 [1/s]")
        self._leader_builder.gain = float(value)

    @property
    def hard_bounds(self) -> bool:
        """Whether the solver claims hard limits (False for the paper's methods)."""
        return self._hard_bounds

    def reset(self) -> None:
        """Forget the warm start (call between unrelated runs)."""
        self._x_prev = None

    def _checked(self, state: DualArmState) -> DualArmState:
        """``state`` with float arrays of the right lengths, or a clear error."""
        q_l = self.task.leader.check_q(state.q_l, "leader joints q_l")
        q_f = self.task.follower.check_q(state.q_f, "follower joints q_f")
        try:
            t, sigma = float(state.t), float(state.sigma)
        except (TypeError, ValueError) as err:
            raise InvalidInputError(f"state t and sigma must be numbers: {err}") from err
        if not (math.isfinite(t) and math.isfinite(sigma)):
            raise NonFiniteError("state t or sigma")
        if q_l is state.q_l and q_f is state.q_f and t is state.t and sigma is state.sigma:
            return state
        return DualArmState(t, q_l, q_f, sigma)

    def step(self, state: DualArmState, *, scale_max: float = 1.0) -> ControlOutput:
        """Compute one step's command from the measured ``state``.

        Parameters
        ----------
        state : DualArmState
            Measured joints of both arms, grasp coordinate and path time.
        scale_max : float
            Largest path-time rate of this step in [0, 1]: the path's feed-forward is
            scaled by it (a rollout passes less than 1 when the path ends within the
            sample).

        Never raises for an infeasible step under the "scale" and "relax" policies:
        the status says what happened. Under "stop" an infeasible step raises
        :class:`~dualarm_qp.errors.InfeasibleStepError` naming the conflicting bounds
        (``ql<i>`` for the leader, with its smallest singular value).

        Raises
        ------
        ShapeError, NonFiniteError, InvalidInputError
            A joint vector of the wrong length or with NaN, a non-finite grasp or time,
            ``scale_max`` outside [0, 1].
        """
        t0 = time.perf_counter()
        if not 0.0 <= scale_max <= 1.0:
            raise InvalidInputError(f"scale_max must be in [0, 1], got {scale_max}")
        state = self._checked(state)
        leader_kin = self.task.leader.fk_jacobian(state.q_l)
        follower_kin = self.task.follower.fk_jacobian(state.q_f)
        sigma_min = (_smallest_singular_value(leader_kin[1]),
                     _smallest_singular_value(follower_kin[1]))
        t1 = time.perf_counter()
        lead = self._leader_builder.build(state.t, state.q_l, *leader_kin, scale_max=scale_max)
        try:
            leader_sol = solve_step(self._leader_solver, lead.problem, policy=self.policy,
                                    tol=self.tolerance)
        except InfeasibleStepError as err:
            raise InfeasibleStepError(
                f"the leader's step is infeasible within its limits (smallest singular "
                f"value of its Jacobian {sigma_min[0]:.3g})", conflicts=err.conflicts) from None
        if lead.recovering.any() and (leader_sol.status is Status.OPTIMAL):
            leader_sol = replace(leader_sol, status=Status.RECOVERING)
        t3 = time.perf_counter()
        n_f = self._builder.n - 1
        if not leader_sol.status.usable:
            self._x_prev = None
            return self._done(ControlOutput(
                ql_dot=np.zeros(self.task.leader.n), qf_dot=np.zeros(n_f), m=0.0, scale=0.0,
                status=leader_sol.status, solution=leader_sol, build=None, leader=lead,
                leader_solution=leader_sol, sigma_min=sigma_min,
                times=StepTimes(t1 - t0, 0.0, 0.0, 0.0, t3 - t1), applied=False))
        ql_dot = _inside(leader_sol.x, lead.problem) if self._hard_bounds else leader_sol.x
        build = self._builder.build(state, ql_dot, leader_kin=leader_kin,
                                    follower_kin=follower_kin, x_prev=self._x_prev)
        t4 = time.perf_counter()
        solution = solve_step(self.solver, build.problem, policy=self.policy,
                              tol=self.tolerance, fallback=self.fallback)
        t5 = time.perf_counter()
        # Every solution is verified with our tolerances before it is applied; registered
        # solvers already did that (they verify before returning), so it is done here
        # only for a solution verified otherwise or not at all.
        if not _verified_with(solution, self.tolerance):
            solution = verify(build.problem, solution, self.tolerance,
                              claims_bounds=self._hard_bounds)
        t6 = time.perf_counter()

        status = solution.status
        if (status is Status.OPTIMAL or status is Status.FEASIBLE) and build.recovering.any():
            status = Status.RECOVERING
            solution = replace(solution, status=status)
        if not self._hard_bounds and status is Status.VIOLATION:
            # The paper's methods ignore the bounds by design: integrate a bound
            # violation and report it, but never a step whose equality is broken.
            usable_x = solution.eq_residual <= equality_limit(build.problem, self.tolerance)
        else:
            usable_x = status.usable
        if not usable_x:
            x = np.zeros(n_f + 1)
        elif self._hard_bounds:
            x = _inside(solution.x, build.problem)
        else:
            x = solution.x
        self._x_prev = x if usable_x else None
        follower_scale = min(max(solution.scale, 0.0), 1.0) if usable_x else 0.0
        scale = scale_max * leader_sol.scale * follower_scale
        return self._done(ControlOutput(
            ql_dot=ql_dot if follower_scale == 1.0 else ql_dot * follower_scale,
            qf_dot=x[:n_f].copy(),
            m=float(x[n_f]),
            scale=scale,
            status=status,
            solution=solution,
            build=build,
            leader=lead,
            leader_solution=leader_sol,
            sigma_min=sigma_min,
            times=StepTimes(t1 - t0, t4 - t3, t5 - t4, t6 - t5, t3 - t1),
            applied=usable_x,
        ))

    def _done(self, out: ControlOutput) -> ControlOutput:
        """Hand ``out`` to the ``on_step`` hook, then return it."""
        if self.on_step is not None:
            self.on_step(out)
        return out


def _inside(x: FloatArray, problem: StepProblem) -> FloatArray:
    """``x`` clipped to the problem's box.

    A verified answer may pass a bound by up to the bound tolerance (1e-7 per s); the
    clip removes that, so that the integrated motion keeps the ranges exactly rather
    than to ``tolerance * dt``. It moves ``A x`` by at most ``|A|`` times that much.
    """
    return np.minimum(np.maximum(x, problem.lower), problem.upper)


def _smallest_singular_value(J: FloatArray) -> float:
    """Smallest singular value of the joint Jacobian ``J``.

    0 when ``J`` has fewer columns than rows (fewer joints than task rows: the arm is
    singular in the task space everywhere) or none.
    """
    m, n = J.shape
    if n < m or n == 0:
        return 0.0
    return float(np.linalg.svd(J, compute_uv=False)[-1])


def _verified_with(solution: StepSolution, tol: Tolerance) -> bool:
    """Whether :func:`verify` checked ``solution`` against tolerances equal to ``tol``."""
    checked = solution.verified_with
    return checked is tol or (checked is not None and checked == tol)
