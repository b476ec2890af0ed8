"""Turn a validated :class:`ExperimentConfig` into library objects, in SI units.

:func:`build_experiment` builds an :class:`~.experiment.Experiment` part by part, each
in its own module: the file's values in SI (:mod:`.setup_values`), the object's surfaces,
grasps and load (:mod:`.setup_object`), the path (:mod:`.setup_path`), the arms
(:mod:`.setup_arms`), the start and the follower's base (:mod:`.setup_initial`), the
collision scene (:mod:`.setup_scene`), the run's limits and the step's options
(:mod:`.setup_controller`) and the solver (:mod:`.setup_solver`); the checks against the
arms are in :mod:`.setup_checks`. ``Experiment`` is importable from here too.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..control.run_limits import RunLimits
from ..errors import ConfigError, DualArmError, InvalidInputError, PairingError
from ..solvers.registry import check_pairing, solver_info
from ..step.build import StepBuilder
from ..step.parts import CostTerm, Limit, Task
from ..step.state import DualArmState
from ..task.scene import DualArmTask
from .config import MIN_DT_S, ExperimentConfig
from .experiment import Experiment
from .options import SolverFlagError, SolverOptions
from .setup_arms import arms_of
from .setup_checks import check_within_reach
from .setup_controller import run_limits_of, step_options_of
from .setup_initial import follower_base, follower_initial, leader_initial
from .setup_jerk import with_jerk_limits
from .setup_object import Grasps, check_load, grasps_of, load_of, surface_of
from .setup_path import path_targets, trajectory_of
from .setup_scene import scene_of
from .setup_solver import check_projection, fallback_of, solver_options_of
from .setup_values import Scales, at_key

FloatArray = NDArray[np.float64]


def build_experiment(
    cfg: ExperimentConfig,
    path: str = "<config>",
    *,
    solver: str | None = None,
    solver_options: SolverOptions | None = None,
    limits: Sequence[Limit] = (),
    tasks: Sequence[Task] = (),
    costs: Sequence[CostTerm] = (),
    dt: float | None = None,
) -> Experiment:
    """Build the task, initial state and controller settings of an experiment.

    Parameters
    ----------
    cfg : ExperimentConfig
        A validated configuration.
    path : str
        File name, for error messages.
    solver : str, optional
        Override of the configured solver name.
    solver_options : mapping, optional
        Options per solver name from the command line
        (:func:`~dualarm_qp.experiments.options.parse_solver_options`); those of the
        solver that runs are applied over the file's (which only the file's solver gets:
        :mod:`.setup_solver`).
    limits : sequence of Limit
        Limits of the user's added to the step (:mod:`dualarm_qp.step.parts`), checked
        against the solver here (a limit that gives rows needs a solver that takes
        rows).
    tasks : sequence of Task
        Tasks of the user's added to the step: equality rows, or with a ``weight`` a
        term of the cost (``examples/custom_task.py``).
    costs : sequence of CostTerm
        Cost terms of the user's, summed with the paper's centring.
    dt : float, optional
        Sampling interval [s] instead of the file's ``controller.dt`` (e.g. 1e-3 for a
        1 kHz loop). The gains and the range-centring horizon the file leaves to their
        default (``1/dt``, ``dt``) follow it.

    Raises
    ------
    ConfigError
        Inconsistent values that the schema cannot catch (wrong number of joints,
        an IK branch that does not exist, a follower base that does not close the grasp,
        an option the file's solver refuses, ...), naming the file and key.
    InvalidInputError
        A command-line option the running solver refuses, naming ``--solver-option``;
        a ``dt`` that is not a finite number of at least 1e-6 s.
    PairingError
        A limit that gives rows (of ``limits`` or of the file) with a solver that takes
        boxes only: the message names the file (and the key ``solver.name`` when the
        file chose the solver), the solver, the limit and the solvers that can.
    """
    if dt is not None and not (math.isfinite(dt) and dt >= MIN_DT_S):
        raise InvalidInputError(f"dt must be a sampling interval of at least {MIN_DT_S:g} s, "
                                f"got {dt!r}")
    try:
        exp = _build(cfg, path, solver, solver_options, dt)
        exp.limits_extra, exp.tasks_extra, exp.costs_extra = (
            tuple(limits), tuple(tasks), tuple(costs))
        builder = StepBuilder(exp.task, exp.options, limits=exp.limits_extra,
                              tasks=exp.tasks_extra, costs=exp.costs_extra)
        check_pairing(solver_info(exp.solver_name), builder.row_limits, builder.full_cost)
        return exp
    except ConfigError as err:
        if err.path is None:
            raise ConfigError(str(err), path=path) from None
        raise
    except PairingError as err:
        where = f"{path}: key 'solver.name': " if solver is None else f"{path}: "
        raise PairingError(f"{where}{err}", solver=err.solver, limits=err.limits,
                           able=err.able) from None
    except SolverFlagError:
        raise
    except DualArmError as err:
        raise ConfigError(str(err), path=path) from None


def _build(cfg: ExperimentConfig, path: str, solver: str | None,
           cli_options: SolverOptions | None, dt_s: float | None = None) -> Experiment:
    """Return the experiment of ``cfg``: each part in turn, in the order its errors are met."""
    solver_options = solver_options_of(cfg, path, solver, cli_options)
    sc = Scales.of(cfg)
    c = cfg.controller
    dt, duration = c.dt * sc.time if dt_s is None else float(dt_s), c.duration * sc.time
    if dt < MIN_DT_S:
        raise ConfigError(f"dt is {dt:.3g} s; the shortest sampling interval is "
                          f"{MIN_DT_S:g} s", path=path, key="controller.dt")
    notes: dict[str, Any] = {}
    with at_key("object.surface", path):
        surface = surface_of(cfg.object.surface, sc, "object.surface")
    with at_key("trajectory", path):
        trajectory = trajectory_of(cfg, sc, duration)
    grasps = grasps_of(cfg, sc, surface, trajectory, path, notes)
    limits = run_limits_of(cfg, sc, path)
    leader, follower = arms_of(cfg, sc, path)
    base_f, q_f0 = follower_base(cfg, sc, follower, trajectory, grasps.surface, grasps.sigma0,
                                 path, notes)
    with at_key("follower", path):
        task = DualArmTask(leader, follower.with_base(base_f), grasps.H1, grasps.surface,
                           trajectory, leader_surface=grasps.leader_surface,
                           contact=grasps.contact,
                           load=None if cfg.object.mass is None else load_of(cfg, sc, path))
    task, q_l0, q_f0 = _started(cfg, sc, task, grasps, q_f0, limits, dt, path, notes)
    options = step_options_of(cfg, sc, dt, task.leader, task.follower, path)
    fallback = fallback_of(cfg, path)
    solver_name = solver or cfg.solver.name
    check_projection(cfg, solver_name, path)
    task, options = with_jerk_limits(cfg, task, options, sc.angle, sc.length, sc.time, path)
    return Experiment(
        name=cfg.name,
        path=path,
        task=task,
        initial=DualArmState(trajectory.t0, q_l0, q_f0, grasps.sigma0, grasps.sigma_l0),
        options=options,
        solver_name=solver_name,
        solver_options=solver_options,
        leader_gain=float(options.leader_gain or 0.0),
        policy=c.policy,
        duration=duration,
        limits=limits,
        project=c.projection,
        fallback=fallback,
        notes=notes,
        initial_rates=c.initial_rates,
    )


def _started(cfg: ExperimentConfig, sc: Scales, task: DualArmTask, grasps: Grasps,
             q_f0: FloatArray | None, limits: RunLimits, dt: float, path: str,
             notes: dict[str, Any]) -> tuple[DualArmTask, FloatArray, FloatArray]:
    """Return the task with its collision scene, and both arms' initial joints, checked.

    The leader's path must be within its reach; the load must be held at the start; the
    scene is made at the initial joints (its pairs that overlap there are left out).
    """
    sigma0, sigma_l0 = grasps.sigma0, grasps.sigma_l0
    check_within_reach(cfg, task.leader, "leader", path_targets(cfg, task, sigma_l0, path),
                       path)
    q_l0 = leader_initial(cfg, task, sc, path, notes, limits.tracking, sigma_l0)
    if q_f0 is None:
        q_f0 = follower_initial(cfg, task, sc, path, notes, q_l0, sigma0, limits.closure,
                                sigma_l0)
    check_load(task, q_l0, sigma0, sigma_l0, path)
    scene = scene_of(cfg, sc.length, sc.angle, sc.time, task.leader, task.follower,
                     (q_l0, q_f0, task.leader.fk(q_l0) @ task.H1_at(sigma_l0)), dt, path)
    if scene is not None:
        task = dataclasses.replace(task, scene=scene)
    return task, q_l0, q_f0


__all__ = ["Experiment", "build_experiment"]
