"""A ready-to-run experiment (:class:`Experiment`): the task, the start, the settings.

Built from a file by :func:`~dualarm_qp.experiments.setup.build_experiment`; its
:meth:`Experiment.controller` is the one place a controller is built from an experiment.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..control.controller import ControlOutput, DualArmController
from ..control.run_limits import RunLimits
from ..solvers.base import DEFAULT_TOLERANCE, Tolerance
from ..solvers.policy import Policy
from ..solvers.registry import get_solver, solver_info
from ..step.options import StepOptions
from ..step.parts import CostTerm, Limit, Task
from ..step.state import DualArmState
from ..task.scene import DualArmTask

FloatArray = NDArray[np.float64]


@dataclass
class Experiment:
    """A ready-to-run experiment.

    Attributes
    ----------
    name : str
        Experiment name from the file.
    path : str
        File it was read from.
    task : DualArmTask
        Arms, object, surface and path in SI units.
    initial : DualArmState
        Initial joints and grasp.
    options : StepOptions
        Step-problem settings.
    solver_name : str
        Registry name of the solver.
    solver_options : dict
        Options handed to the solver's factory.
    leader_gain : float
        Leader tracking gain [1/s].
    policy : str
        Infeasible-step policy.
    duration : float
        Run length [s].
    limits : RunLimits
        Tolerances, singularity threshold and duration cap of the run.
    project : bool or None
        Position-level drift correction in the rollout (None: the default for the
        solver, see :func:`~dualarm_qp.control.rollout.rollout`).
    fallback : str or None
        Solver for a feasible step the configured hard-limit solver fails on.
    notes : dict
        Reconstruction facts worth reporting (leader IK branch, follower base, ...).
    initial_rates : {"rest", "path"}
        How the run starts: at rest, or moving as the path's first step asks
        (:meth:`start_rates`).
    limits_extra : tuple of Limit
        Limits of the user's added to the step (``limits=`` of the controller).
    tasks_extra : tuple of Task
        Tasks of the user's added to the step (``tasks=`` of the controller).
    costs_extra : tuple of CostTerm
        Cost terms of the user's added to the step (``costs=`` of the controller).
    """

    name: str
    path: str
    task: DualArmTask
    initial: DualArmState
    options: StepOptions
    solver_name: str
    solver_options: dict[str, Any]
    leader_gain: float
    policy: Policy
    duration: float
    limits: RunLimits = field(default_factory=RunLimits)
    project: bool | None = None
    fallback: str | None = "nullspace"
    notes: dict[str, Any] = field(default_factory=dict)
    initial_rates: str = "rest"
    limits_extra: tuple[Limit, ...] = ()
    tasks_extra: tuple[Task, ...] = ()
    costs_extra: tuple[CostTerm, ...] = ()

    def controller(
        self,
        *,
        fallback: bool = True,
        tolerance: Tolerance | None = None,
        on_step: Callable[[ControlOutput], None] | None = None,
        acceleration_limits: bool | None = None,
    ) -> DualArmController:
        """Return a fresh controller with the configured solver.

        The one place a controller is built from an experiment (runs, the bench, the
        step-suite generator).

        Parameters
        ----------
        fallback : bool
            False leaves out the fallback solver (the bench measures each solver's own
            success).
        tolerance : Tolerance, optional
            What counts as meeting the equality and the bounds (default
            :data:`~dualarm_qp.solvers.base.DEFAULT_TOLERANCE`).
        on_step : callable, optional
            Called with every step's :class:`~dualarm_qp.control.controller.ControlOutput`
            (see :class:`~dualarm_qp.control.controller.DualArmController`).
        acceleration_limits : bool, optional
            Override the configured ``acceleration_limits`` (:meth:`start_rates` solves
            the first step without them).

        Raises
        ------
        PairingError
            A limit that gives rows with a solver that takes boxes only.
        """
        solver = get_solver(self.solver_name, **self.solver_options)
        backup = None
        if (fallback and self.fallback is not None and self.fallback != self.solver_name
                and solver_info(self.solver_name).hard_bounds):
            backup = get_solver(self.fallback)
        # A step may leave half of the run's tracking and closure tolerances at the next
        # sample (the lookahead slows it otherwise): the other half is the feedback's.
        budget = (0.5 * min(self.limits.tracking[0], self.limits.closure[0]),
                  0.5 * min(self.limits.tracking[1], self.limits.closure[1]))
        options = self.options
        if acceleration_limits is not None:
            options = dataclasses.replace(options, acceleration_limits=acceleration_limits)
        return DualArmController(self.task, solver, options,
                                 leader_gain=self.leader_gain, policy=self.policy,
                                 tolerance=DEFAULT_TOLERANCE if tolerance is None else tolerance,
                                 fallback=backup, on_step=on_step, error_budget=budget,
                                 singularity_escape=self.limits.singular_value_min or 1e-3,
                                 limits=self.limits_extra, tasks=self.tasks_extra,
                                 costs=self.costs_extra)

    def start_rates(self) -> FloatArray | None:
        """Return the rates the run starts with [rad/s, m/s] (decision order), or None.

        With ``initial_rates: path`` the pair is taken to move already as the path's
        first step asks: that step's answer without acceleration limits.
        """
        if self.initial_rates == "rest":
            return None
        free = self.controller(acceleration_limits=False)
        out = free.step(self.initial)
        if not out.applied:
            return None
        return free.layout.join(out.ql_dot, out.qf_dot, out.m, out.m_leader)


__all__ = ["Experiment"]
