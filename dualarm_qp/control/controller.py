"""The per-step controller: measured state in, joint rates and sliding speed out.

The controller stands on its own so that it can be dropped into a real control loop:
call :meth:`DualArmController.step` once per sample with the measured joints of both
arms, the grasp coordinate and the path time; apply ``ql_dot`` to the leader,
``qf_dot`` to the follower and let the grasp slide at ``m``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidInputError
from ..se3 import pose_error
from ..solvers.base import DEFAULT_TOLERANCE, Status, StepSolution, StepSolver, Tolerance, verify
from ..solvers.policy import Policy, solve_step
from ..solvers.registry import solver_info
from ..step.build import DualArmState, StepBuild, StepOptions, build_step
from ..task.scene import DualArmTask

FloatArray = NDArray[np.float64]

POLICIES: tuple[Policy, ...] = ("scale", "relax", "stop")


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
    leader_gain : float
        Feedback gain [1/s] of the leader's tracking of ``D(t)``.
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
        leader_gain: float = 0.0,
        policy: Policy = "scale",
        tolerance: Tolerance = DEFAULT_TOLERANCE,
    ) -> None:
        if policy not in POLICIES:
            raise InvalidInputError(f"policy must be one of {POLICIES}, got {policy!r}")
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
        except Exception:  # a solver not from the registry: assume it claims the bounds
            self._hard_bounds = True
        self._H1_inv = task.H1_inv
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
        D = traj.pose(t)
        V = traj.twist(t)
        T_target = D @ self._H1_inv
        # Velocity of the leader's tool origin: v_o + w x (p_l - p_o).
        r = T_target[:3, 3] - D[:3, 3]
        w = V[3:]
        V_l = V.copy()
        V_l[:3] += np.array(
            [w[1] * r[2] - w[2] * r[1], w[2] * r[0] - w[0] * r[2], w[0] * r[1] - w[1] * r[0]]
        )
        err = pose_error(T_target, T_l)
        if self.leader_gain > 0:
            V_l += self.leader_gain * err
        ql_dot: FloatArray
        try:
            ql_dot = np.linalg.solve(J_l, V_l)
        except np.linalg.LinAlgError:  # singular or not square: least squares
            ql_dot = np.linalg.lstsq(J_l, V_l, rcond=None)[0]
        return ql_dot, err

    def step(self, state: DualArmState) -> ControlOutput:
        """Compute one step's command from the measured ``state``.

        Never raises for an infeasible step under the "scale" and "relax" policies:
        the status says what happened. Under "stop" an infeasible step raises
        :class:`~dualarm_qp.errors.InfeasibleStepError` naming the conflicting bounds.
        """
        t0 = time.perf_counter()
        leader_kin = self.task.leader.fk_jacobian(state.q_l)
        follower_kin = self.task.follower.fk_jacobian(state.q_f)
        t1 = time.perf_counter()
        ql_dot, leader_err = self.leader_rates(state.t, *leader_kin)
        build = build_step(
            self.task, state, ql_dot, self.options,
            leader_kin=leader_kin, follower_kin=follower_kin, x_prev=self._x_prev,
        )
        t2 = time.perf_counter()
        solution = solve_step(self.solver, build.problem, policy=self.policy, tol=self.tolerance)
        t3 = time.perf_counter()
        solution = verify(build.problem, solution, self.tolerance,
                          claims_bounds=self._hard_bounds)
        t4 = time.perf_counter()

        status = solution.status
        if status is Status.OPTIMAL and build.recovering.any():
            status = Status.RECOVERING
        if not self._hard_bounds and status is Status.VIOLATION:
            # The paper's methods ignore the bounds by design; integrate and report.
            usable_x = True
        else:
            usable_x = status.usable
        n_f = self.task.follower.n
        x = solution.x if usable_x else np.zeros(n_f + 1)
        self._x_prev = x if usable_x else None
        scale = min(max(solution.scale, 0.0), 1.0) if usable_x else 0.0
        solution = replace(solution, status=status)
        return ControlOutput(
            ql_dot=ql_dot * scale,
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
