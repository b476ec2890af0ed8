"""The per-step controller: measured state in, joint rates and sliding speed out.

The controller stands on its own so that it can be dropped into a real control loop:
call :meth:`DualArmController.step` once per sample with the measured joints of both
arms, the grasp coordinate and the path time; apply ``ql_dot`` to the leader,
``qf_dot`` to the follower and let the grasp slide at ``m``.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray
from scipy.linalg import lapack

from ..errors import InvalidInputError, NonFiniteError, SolverNotFoundError
from ..se3 import compose_rows, pose_error_rows
from ..solvers.base import DEFAULT_TOLERANCE, Status, StepSolution, StepSolver, Tolerance, verify
from ..solvers.policy import POLICIES, Policy, solve_step
from ..solvers.registry import solver_info
from ..step.build import DualArmState, StepBuild, StepBuilder, StepOptions
from ..task.scene import DualArmTask

FloatArray = NDArray[np.float64]



@dataclass(frozen=True)
class StepTimes:
    """Wall-clock split of one controller step [s]."""

    kinematics: float
    assembly: float
    solve: float
    verify: float

    @property
    def total(self) -> float:
        """Whole controller step [s]."""
        return self.kinematics + self.assembly + self.solve + self.verify


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
        Task scale applied this step (1.0 = full speed along the path).
    status : Status
        Solver status, or RECOVERING when a variable started outside its range and
        the solver met the bounds that pull it back.
    solution : StepSolution
        The verified solver output.
    build : StepBuild
        The step problem and what the builder noticed.
    leader_error : ndarray, shape (6,)
        Leader tool pose error to its target ``D(t) H1^-1`` [m, rad].
    times : StepTimes
        Timing split of the step.
    applied : bool
        Whether the command is meant to be applied. True for every usable status,
        and for a bound VIOLATION of a method that ignores bounds by design (the
        paper's reference step); False otherwise (the rates are then zero).
    """

    ql_dot: FloatArray
    qf_dot: FloatArray
    m: float
    scale: float
    status: Status
    solution: StepSolution
    build: StepBuild
    leader_error: FloatArray
    times: StepTimes
    applied: bool


class DualArmController:
    """Leader tracking plus the redundancy-resolved follower step.

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
    ) -> None:
        if policy not in POLICIES:
            raise InvalidInputError(f"policy must be one of {POLICIES}, got {policy!r}")
        if leader_gain is None:
            leader_gain = 1.0 / options.dt
        if not (np.isfinite(leader_gain) and leader_gain >= 0):
            raise InvalidInputError("leader_gain must be a finite number >= 0 [1/s]")
        self.task = task
        self.solver = solver
        self.options = options
        self.leader_gain = leader_gain
        self.policy = policy
        self.tolerance = tolerance
        try:
            self._hard_bounds = solver_info(solver.name).hard_bounds
        except SolverNotFoundError:  # a solver not from the registry: it claims the bounds
            self._hard_bounds = True
        self._builder = StepBuilder(task, options)
        # The object frame is often the leader's tool frame: skip composing with I.
        self._H1_inv = None if np.array_equal(task.H1, np.eye(4)) else task.H1_inv.tolist()
        self._x_prev: FloatArray | None = None

    def reset(self) -> None:
        """Forget the warm start (call between unrelated runs)."""
        self._x_prev = None

    def leader_rates(
        self, t: float, T_l: FloatArray, J_l: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """Leader joint rates that move the object along ``D(t)`` [rad/s].

        Feed-forward of the object's twist at the leader's tool plus feedback of the
        leader's pose error. Returns ``(ql_dot, error)``.
        """
        traj = self.task.trajectory
        D = traj.pose(t).tolist()
        V = traj.twist(t).tolist()
        T_target = D if self._H1_inv is None else compose_rows(D, self._H1_inv)
        # Velocity of the leader's tool origin: v_o + w x (p_l - p_o).
        r0 = T_target[0][3] - D[0][3]
        r1 = T_target[1][3] - D[1][3]
        r2 = T_target[2][3] - D[2][3]
        w0, w1, w2 = V[3], V[4], V[5]
        V_l = [V[0] + (w1 * r2 - w2 * r1), V[1] + (w2 * r0 - w0 * r2),
               V[2] + (w0 * r1 - w1 * r0), w0, w1, w2]
        err = pose_error_rows(T_target, T_l.tolist())
        if self.leader_gain > 0:
            V_l = [v + self.leader_gain * e for v, e in zip(V_l, err, strict=True)]
        twist = np.array(V_l)
        ql_dot: FloatArray = twist
        info = -1
        if J_l.shape[0] == J_l.shape[1]:
            # LAPACK gesv directly: np.linalg.solve costs several times more at 6 x 6.
            ql_dot, info = lapack.dgesv(J_l, twist)[2:]
        if info != 0:  # singular or not square: least squares
            ql_dot = np.linalg.lstsq(J_l, twist, rcond=None)[0]
        return ql_dot, np.array(err)

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

    def step(self, state: DualArmState) -> ControlOutput:
        """Compute one step's command from the measured ``state``.

        Never raises for an infeasible step under the "scale" and "relax" policies:
        the status says what happened. Under "stop" an infeasible step raises
        :class:`~dualarm_qp.errors.InfeasibleStepError` naming the conflicting bounds.

        Raises
        ------
        ShapeError, NonFiniteError, InvalidInputError
            A joint vector of the wrong length or with NaN, a non-finite grasp or time.
        """
        t0 = time.perf_counter()
        state = self._checked(state)
        leader_kin = self.task.leader.fk_jacobian(state.q_l)
        follower_kin = self.task.follower.fk_jacobian(state.q_f)
        t1 = time.perf_counter()
        ql_dot, leader_err = self.leader_rates(state.t, *leader_kin)
        build = self._builder.build(state, ql_dot, leader_kin=leader_kin,
                                    follower_kin=follower_kin, x_prev=self._x_prev)
        t2 = time.perf_counter()
        solution = solve_step(self.solver, build.problem, policy=self.policy, tol=self.tolerance)
        t3 = time.perf_counter()
        # Every solution is verified with our tolerances before it is applied; registered
        # solvers already did that (they verify before returning), so it is done here
        # only for a solution verified otherwise or not at all.
        if not _verified_with(solution, self.tolerance):
            solution = verify(build.problem, solution, self.tolerance,
                              claims_bounds=self._hard_bounds)
        t4 = time.perf_counter()

        status = solution.status
        if (status is Status.OPTIMAL or status is Status.FEASIBLE) and build.recovering.any():
            status = Status.RECOVERING
            solution = replace(solution, status=status)
        if not self._hard_bounds and status is Status.VIOLATION:
            # The paper's methods ignore the bounds by design; integrate and report.
            usable_x = True
        else:
            usable_x = status.usable
        n_f = self._builder.n - 1
        x = solution.x if usable_x else np.zeros(n_f + 1)
        self._x_prev = x if usable_x else None
        scale = min(max(solution.scale, 0.0), 1.0) if usable_x else 0.0
        return ControlOutput(
            ql_dot=ql_dot if scale == 1.0 else ql_dot * scale,
            qf_dot=x[:n_f].copy(),
            m=float(x[n_f]),
            scale=scale,
            status=status,
            solution=solution,
            build=build,
            leader_error=leader_err,
            times=StepTimes(t1 - t0, t2 - t1, t3 - t2, t4 - t3),
            applied=usable_x,
        )


def _verified_with(solution: StepSolution, tol: Tolerance) -> bool:
    """Whether :func:`verify` checked ``solution`` against tolerances equal to ``tol``."""
    checked = solution.verified_with
    return checked is tol or (checked is not None and checked == tol)
