"""The rollout: integrate the controller along the path, record it, and judge the run.

A run **completes** only when the task was done:

* the whole path was executed (path time at its end; under the ``"scale"`` policy the
  run goes on past the nominal duration, up to ``duration_cap``);
* the leader tracked ``D(t)`` and the grasp closure held, within their tolerances;
* for a solver that claims hard limits, the realised motion (:mod:`.realised`) kept
  every limit of both arms and of the grasp.

Otherwise it **fails**, and :class:`~.failure.Failure` names the criterion, the sample
and the amount. Every sample is kept either way.

A rollout runs in four phases, one module each: the checks before the first sample
(:mod:`.preflight`), the loop over the samples (:mod:`.run_loop`, with the per-sample
criteria of :mod:`.sample_checks` and the corrections of :mod:`.corrections`), then the
verdict (:mod:`.verdict`), which reads the realised checks of the recorded motion
(:mod:`.realised_checks`). The names a rollout's caller needs are importable from here.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidInputError
from ..step.state import DualArmState
from .controller import DualArmController
from .corrections import Corrections
from .failure import CRITERIA, EXPLAINED, Failure
from .plant import Plant
from .preflight import before_the_run
from .realised_checks import clearance_failure, realised_reports, torque_failure
from .result import RolloutResult
from .run_limits import SINGULARITY_ACTIONS, RunLimits
from .run_loop import LoopOutcome, SampleLoop
from .trace import Trace
from .verdict import Verdict, judge

FloatArray = NDArray[np.float64]


def rollout(
    controller: DualArmController,
    initial: DualArmState,
    *,
    duration: float,
    limits: RunLimits | None = None,
    reresolve_orientation: bool | None = None,
    project: bool | None = None,
    progress: Callable[[float, float], None] | None = None,
    stop_on_interrupt: bool = False,
    preflight: bool = True,
    initial_rates: FloatArray | None = None,
    plant: Plant | None = None,
) -> RolloutResult:
    """Run ``controller`` from ``initial`` along ``duration`` seconds of path.

    The run ends when the path time reaches ``initial.t + duration``; a slowed task runs
    longer, up to ``limits.duration_cap`` (the samples: :mod:`.run_loop`).

    Parameters
    ----------
    controller : DualArmController
        The per-step controller.
    initial : DualArmState
        State at path time ``initial.t``.
    duration : float
        Length of the path [s].
    limits : RunLimits, optional
        Tolerances, singularity threshold and cap (defaults: :class:`RunLimits`).
    reresolve_orientation, project : bool, optional
        The Sec. 3.3 re-resolution and the drift projection after each step; default:
        for the paper's methods (:meth:`.corrections.Corrections.chosen`).
    progress : callable, optional
        Called as ``progress(path_done, time_lost)`` after every sample: the share of
        the path executed, in [0, 1], and the time lost to slowing so far [s] (as
        :attr:`RolloutResult.time_lost`). It may raise KeyboardInterrupt to stop the run.
    stop_on_interrupt : bool
        On KeyboardInterrupt during the samples, return the samples completed so far,
        failing on ``"interrupted"``; by default the exception propagates.
    preflight : bool
        Refuse a run before its first sample when :func:`.preflight.before_the_run` finds
        a waypoint out of reach, a torque or a clearance beyond its limit at the start,
        or a path through an obstacle. Default True.
    initial_rates : ndarray, optional
        The rates at the start [rad/s, m/s], in the controller's decision order (default
        zero); acceleration limits and their realised check start from them.
    plant : Plant, optional
        What the commands drive (:mod:`.plant`); default the command integrated exactly.

    Returns
    -------
    RolloutResult
        Never raises for a failed step: it says why, with every completed sample.

    Raises
    ------
    InvalidInputError
        A non-positive duration, a cap below it, or a correction for a hard-limit solver.
    """
    limits, cap = _checked(duration, limits)
    corrections = Corrections.chosen(controller, initial, reresolve_orientation, project, plant)
    trace, start = _first_sample(controller, initial, cap)
    dt, path_start, path_end = controller.options.dt, start.t, start.t + duration
    controller.reset(initial_rates)
    v_start = controller.applied
    refused = before_the_run(controller, start, path_end) if preflight else None
    if refused is not None:
        empty = trace.truncate(0)
        return RolloutResult(empty, refused[0], controller.solver.name, dt, path_start,
                             path_end, realised_reports(controller, empty, dt, v_start),
                             controller.hard_bounds, extras=refused[1])
    if plant is not None:  # after the preflight: a run it refuses does not pay the settle
        plant.reset(start, dt)
    loop = SampleLoop(controller, trace, start, duration=duration, limits=limits,
                      corrections=corrections, plant=plant,
                      progress=progress).run(stop_on_interrupt=stop_on_interrupt)
    verdict = judge(controller, loop, v_start=v_start, path_start=path_start,
                    duration=duration, cap=cap, plant=plant)
    return _result(controller, loop, verdict, (path_start, path_end), corrections, limits,
                   cap)


def _checked(duration: float, limits: RunLimits | None) -> tuple[RunLimits, float]:
    """Return the run's limits (the defaults for None) and its cap [s], checked."""
    if not (math.isfinite(duration) and duration > 0):
        raise InvalidInputError(f"duration must be a positive number of seconds, got {duration}")
    limits = RunLimits() if limits is None else limits
    cap = 2.0 * duration if limits.duration_cap is None else limits.duration_cap
    if not cap >= duration:
        raise InvalidInputError(f"duration_cap ({cap:g} s) must be at least the duration "
                                f"({duration:g} s)")
    return limits, cap


def _first_sample(controller: DualArmController, initial: DualArmState, cap: float
                  ) -> tuple[Trace, DualArmState]:
    """Return the rows for a run of at most ``cap`` [s], and the checked start state."""
    task, dt = controller.task, controller.options.dt
    trace = Trace.allocate(math.floor(cap / dt + 1e-9) + 1, task.leader.n, task.follower.n)
    start = DualArmState(float(initial.t),
                         task.leader.check_q(initial.q_l, "initial q_l").copy(),
                         task.follower.check_q(initial.q_f, "initial q_f").copy(),
                         float(initial.sigma), float(initial.sigma_leader))
    return trace, start


def _result(controller: DualArmController, loop: LoopOutcome, verdict: Verdict,
            span: tuple[float, float], corrections: Corrections, limits: RunLimits,
            cap: float) -> RolloutResult:
    """Return the result of a run that started: its samples, its verdict, its settings.

    ``span`` holds the path time at the start and at the end of the task [s].
    """
    scene, loads = controller.task.scene, verdict.loads
    return RolloutResult(
        loop.trace, verdict.failure, controller.solver.name, controller.options.dt,
        span[0], span[1], verdict.realised, controller.hard_bounds, warnings=verdict.warnings,
        clearance=verdict.clearance, torque=verdict.torque,
        extras={**({} if scene is None else {"collision": scene.summary()}),
                **({} if loads is None else {"loads": loads.as_dict()}),
                "projection": corrections.project,
                "reresolve_orientation": corrections.reresolve_orientation,
                "projection_failures": loop.projection_failures,
                "closure_tolerance_m_rad": list(limits.closure),
                "tracking_tolerance_m_rad": list(limits.tracking),
                "singular_value_min": limits.singular_value_min,
                "duration_cap_s": cap})


__all__ = ["CRITERIA", "EXPLAINED", "SINGULARITY_ACTIONS", "Failure", "RolloutResult",
           "RunLimits", "clearance_failure", "rollout", "torque_failure"]
