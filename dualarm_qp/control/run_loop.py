"""The rollout's loop: step the controller sample by sample, record, check, advance.

Each sample: the controller computes the command from the current state; the sample is
recorded and checked (:mod:`.sample_checks`); then the leader integrates
``ql_dot * dt``, the follower ``qf_dot * dt`` and the grasp ``m * dt`` (or a plant
measures where the command took them), the path time advances by ``scale * dt``, and
the position-level corrections run when chosen (:mod:`.corrections`). The loop stops
at the first failure, at the path's end, or when the trace is full.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from ..errors import DualArmError, InfeasibleStepError
from ..step.state import DualArmState
from .conflicts import plainly
from .controller import ControlOutput, DualArmController
from .corrections import Corrections
from .failure import Failure, at
from .plant import Plant, not_followed, planned_errors
from .result import time_lost_to_slowing
from .run_limits import RunLimits
from .sample_checks import sample_failure, stall_failure, step_failure
from .trace import Trace, record, record_state


def end_tolerance(path_end: float) -> float:
    """How close to ``path_end`` [s] the path time counts as at the end [s]."""
    return 1e-9 * max(1.0, abs(path_end))


@dataclass
class LoopOutcome:
    """What the loop left.

    Attributes
    ----------
    trace : Trace
        The samples recorded whole.
    failure : Failure or None
        The first failure found at a sample.
    warnings : list of str
        What a person should know although no sample failed.
    projection_failures : int
        Drift projections that did not converge.
    interrupted : KeyboardInterrupt or None
        The interrupt that stopped the loop (with ``stop_on_interrupt``).
    plant_lag : bool
        The failure is the plant's: it did not follow the command.
    """

    trace: Trace
    failure: Failure | None
    warnings: list[str]
    projection_failures: int
    interrupted: KeyboardInterrupt | None
    plant_lag: bool


class SampleLoop:
    """The samples of one rollout, written into ``trace`` (one row per sample, at most its length).

    Parameters
    ----------
    controller : DualArmController
        The per-step controller (already reset).
    trace : Trace
        Rows for every sample the run may take.
    start : DualArmState
        The state at the first sample.
    duration : float
        Length of the path [s] (the progress is the share of it executed).
    limits : RunLimits
        Tolerances and singularity threshold.
    corrections : Corrections
        The position-level corrections after each step.
    plant : Plant, optional
        What the commands drive (default: the command integrated exactly).
    progress : callable, optional
        Called as ``progress(path_done, time_lost)`` after every sample.
    """

    def __init__(self, controller: DualArmController, trace: Trace, start: DualArmState, *,
                 duration: float, limits: RunLimits, corrections: Corrections,
                 plant: Plant | None = None,
                 progress: Callable[[float, float], None] | None = None) -> None:
        self.controller, self.trace, self.limits = controller, trace, limits
        self.corrections, self.plant, self.progress = corrections, plant, progress
        self.dt = controller.options.dt
        self.path_start = float(start.t)
        self.path_end = self.path_start + duration
        self.duration = duration
        self.end_tol = end_tolerance(self.path_end)
        self.state = start
        self.t_wall = self.path_start
        self.window = (self.t_wall, self.path_start)  # start of the stall-detection window
        self.pre: tuple[float, float] | None = None  # closure error before correction
        self.corr = (0.0, 0.0)
        self.planned: dict[str, tuple[float, float]] | None = None  # the plan's own errors
        self.failure: Failure | None = None
        self.warnings: list[str] = []
        self.rows = 0  # samples recorded whole
        self.projection_failures = 0
        self.plant_lag = False

    def run(self, *, stop_on_interrupt: bool = False) -> LoopOutcome:
        """Run the samples; on KeyboardInterrupt stop there when ``stop_on_interrupt``."""
        interrupted: KeyboardInterrupt | None = None
        try:
            for k in range(len(self.trace)):
                if self._sample(k):
                    break
        except KeyboardInterrupt as exc:
            if not stop_on_interrupt:
                raise
            interrupted = exc
        return LoopOutcome(self.trace.truncate(self.rows), self.failure, self.warnings,
                           self.projection_failures, interrupted, self.plant_lag)

    def _sample(self, k: int) -> bool:
        """Step, record and check sample ``k``, then advance; True when the run stops."""
        state, t = self.state, self.t_wall
        at_end = state.t >= self.path_end - self.end_tol
        scale_max = 0.0 if at_end else min(1.0, (self.path_end - state.t) / self.dt)
        try:
            out = self.controller.step(state, scale_max=scale_max)
        except DualArmError as err:
            self._failed_step(k, state, err, at_end)
            return True
        self._record(k, state, out, at_end)
        self.failure = self._judged(k, state, out, at_end)
        if self.failure is not None:
            return True
        if self.progress is not None:
            self.progress(min((state.t - self.path_start) / self.duration, 1.0),
                          time_lost_to_slowing(t - self.path_start, state.t - self.path_start,
                                               self.dt))
        if at_end or k == len(self.trace) - 1:
            return True
        self._advance(state, out)
        return False

    def _failed_step(self, k: int, state: DualArmState, err: DualArmError,
                     at_end: bool) -> None:
        """Keep the state the step raised at (with no command), and say why."""
        t = self.t_wall
        record_state(self.trace, k, t, state, self.controller,
                     "infeasible" if isinstance(err, InfeasibleStepError) else "error")
        self.rows = k + 1
        message = f"{at(k, t)}: {err}"
        if at_end:  # the path is done; this command would not be applied
            self.warnings.append(f"the command at the path's end failed: {message}")
        else:
            self.failure = step_failure(self.controller, state, k, t, err, message)

    def _record(self, k: int, state: DualArmState, out: ControlOutput, at_end: bool) -> None:
        """Write sample ``k``: the state, its command and the corrections that led to it."""
        tr = self.trace
        record(tr, k, self.t_wall, state, out, self.controller)
        if at_end and k:  # not applied: keep the task scale the path ended at
            tr.scale[k] = tr.scale[k - 1]
        tr.closure_pos_err_pre[k], tr.closure_rot_err_pre[k] = (
            self.pre if self.pre is not None else (tr.closure_pos_err[k], tr.closure_rot_err[k]))
        tr.correction_l[k], tr.correction_f[k] = self.corr
        self.rows = k + 1

    def _judged(self, k: int, state: DualArmState, out: ControlOutput, at_end: bool
                ) -> Failure | None:
        """Return the failure of sample ``k``, or None (see :mod:`.sample_checks`)."""
        limits, t = self.limits, self.t_wall
        # The command at the path's end is not applied: it cannot fail the run.
        failure = sample_failure(self.trace, k, out.applied or at_end, out.status.value,
                                 out.solution.message, limits, self.warnings,
                                 speed_limited=self.controller.options.velocity_limits)
        if failure is not None and self.planned is not None and failure.criterion in (
                "closure", "tracking"):  # measured: was it the plan's own error?
            lagged = not_followed(failure, self.planned, limits.closure
                                  if failure.criterion == "closure" else limits.tracking)
            failure = failure if lagged is None else lagged
            self.plant_lag = lagged is not None
        if failure is not None and failure.criterion == "solver":  # say why, plainly
            failure = plainly(self.controller, state, failure, out.build.problem,
                              out.solution.extras.get("conflicts", ()))
        if failure is None and t - self.window[0] >= limits.stall_time - 1e-9:
            failure = stall_failure(self.trace, k, t, state.t, self.window,
                                    out.solution.message)
            self.window = (t, state.t)
        return failure

    def _advance(self, state: DualArmState, out: ControlOutput) -> None:
        """Move to the next sample: the command applied for ``dt``, then the corrections."""
        if self.plant is None:
            nxt = state.advanced(out, self.dt)
        else:
            nxt = self.plant.advance(state, out, self.dt)
            self.planned = planned_errors(self.controller.task, state, out, self.dt)
        self.t_wall = self.t_wall + self.dt
        self.pre, self.corr = None, (0.0, 0.0)
        self.state = DualArmState(nxt.t, nxt.q_l, nxt.q_f, nxt.sigma, nxt.sigma_leader)
        if self.corrections.any:
            done = self.corrections.apply(self.controller, self.state)
            self.state, self.pre, self.corr = done.state, done.closure_before, done.moved
            self.projection_failures += done.failures


__all__ = ["LoopOutcome", "SampleLoop", "end_tolerance"]
