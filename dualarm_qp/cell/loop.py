"""The drive loop: one loop for every cell (MuJoCo, ROS 2, Franka), on the cell's clock.

Each sample ``k``, at the cell's time ``t0 + k dt``:

1. **read** both arms' measured joints (:meth:`Cell.read <.base.Cell.read>`); a state
   older than ``watchdog`` on the cell's clock, or a joint outside its range by more
   than ``range_margin``, stops the cell;
2. **estimate the grasp** from the two arms' joints (:mod:`.grasp`);
3. **step** the controller from that state (in a dry run: from the model's state,
   integrated from the measured start as ``run`` does);
4. **clamp** the command to the joints' speed, acceleration and jerk limits
   (:mod:`.safety`) and **send** it (not in a dry run);
5. **record** the sample (the columns of ``run``'s ``trajectory.csv`` and the cell's
   own, :data:`CELL_COLUMNS`), hand it to the observer if there is one (a live view, a
   ROS 2 node's topics: :data:`Observer`), then wait for the next sample time.

Whatever ends the loop (the path's end, a failed step, Ctrl-C or SIGTERM, the watchdog,
a state out of range, a cell error), both arms are then brought to rest by the stop ramp
(:class:`~.safety.StopRamp`), with SIGINT and SIGTERM held, and each ramp sample is
recorded too (status ``stopping``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._signals import SignalHold
from ..control.controller import ControlOutput, DualArmController
from ..control.failure import Failure
from ..control.result import RolloutResult
from ..control.run_limits import RunLimits
from ..control.trace import Trace, record, record_margins, record_state
from ..errors import DualArmError, InfeasibleStepError
from ..step.state import DualArmState
from .base import Cell, CellError, Reading
from .grasp import estimate_grasp
from .record import cell_columns, cell_realised, stop_summary
from .safety import CommandLimits, StopRamp

FloatArray = NDArray[np.float64]

#: Called with the trace and the row just recorded (control and stop rows alike); it
#: must not raise (an observer that can fail keeps its own errors).
Observer = Callable[[Trace, int], None]


@dataclass(frozen=True)
class DriveSettings:
    """How the loop guards the cell.

    Parameters
    ----------
    watchdog : float
        Oldest state the controller may act on, on the cell's clock [s].
    dry_run : bool
        Read the robots and compute the commands, but send nothing.
    start_tolerance : float
        Largest distance of a measured joint from the file's start [rad].
    range_margin : float
        How far a measured joint may be outside its range before the cell stops [rad].
    """

    watchdog: float
    dry_run: bool = False
    start_tolerance: float = 0.01
    range_margin: float = 0.0


@dataclass
class DriveResult:
    """What the loop did: the run as ``run`` reports it, and the cell's own record.

    Attributes
    ----------
    result : RolloutResult
        The recorded samples (control samples, then the stop's), the failure if any and
        the realised limits of the control samples.
    columns : dict
        The cell's columns of ``trajectory.csv`` (:func:`.record.cell_columns`).
    cell : dict
        The cell's part of ``summary.json`` (watchdog, clamp, stop, clock).
    """

    result: RolloutResult
    columns: dict[str, Any]
    cell: dict[str, Any] = field(default_factory=dict)


@dataclass
class _Log:
    """The cell's own values per row (the rest goes into the :class:`Trace`)."""

    robot_t: list[float] = field(default_factory=list)
    age: list[float] = field(default_factory=list)
    sent: list[FloatArray] = field(default_factory=list)
    computed: list[FloatArray] = field(default_factory=list)
    sigma_measured: list[float] = field(default_factory=list)
    offset: list[float] = field(default_factory=list)


@dataclass(frozen=True)
class _Sent:
    """The rates sent, as a command the model integrates (a dry run's state)."""

    ql_dot: FloatArray
    qf_dot: FloatArray
    m: float
    m_leader: float
    scale: float


def command_limits(controller: DualArmController) -> CommandLimits:
    """Return the limits every sent command keeps: both arms' speeds, accelerations and jerks."""
    task = controller.task
    arms = (task.leader, task.follower)
    return CommandLimits(np.concatenate([a.qd_max for a in arms]),
                         np.concatenate([a.qdd_max for a in arms]),
                         np.concatenate([a.qddd_max for a in arms]), controller.options.dt)


def _stop_rows(lim: CommandLimits) -> int:
    """Return an upper bound of the stop ramp's samples from any speed within the limits."""
    dt = lim.dt
    bound = 2.0
    for v, a, j in zip(lim.v_max, lim.a_max, lim.j_max, strict=True):
        if math.isfinite(v) and math.isfinite(a):
            bound = max(bound, v / (a * dt) + (a / (j * dt) if math.isfinite(j) else 0.0))
    return int(min(math.ceil(2.0 * bound) + 4, 100_000))


class _Loop:
    """One drive of a cell (see the module); :func:`drive` runs it."""

    def __init__(self, cell: Cell, controller: DualArmController, initial: DualArmState,
                 duration: float, settings: DriveSettings, limits: RunLimits,
                 observer: Observer | None = None) -> None:
        self.cell, self.controller, self.settings, self.limits = cell, controller, settings, limits
        self.observer = observer
        self.task = controller.task
        self.dt = controller.options.dt
        self.initial = initial
        self.path_start = float(initial.t)
        self.path_end = self.path_start + duration
        cap = 2.0 * duration if limits.duration_cap is None else limits.duration_cap
        self.max_rows = math.floor(cap / self.dt + 1e-9) + 1
        self.lim = command_limits(controller)
        n_l, n_f = self.task.leader.n, self.task.follower.n
        self.n_l = n_l
        self.trace = Trace.allocate(self.max_rows + _stop_rows(self.lim), n_l, n_f)
        self.log = _Log()
        self.rows = 0
        self.control_rows = 0
        self.sent1 = np.zeros(n_l + n_f)
        self.sent2 = np.zeros(n_l + n_f)
        self.t0 = 0.0
        self.failure: Failure | None = None
        self.stop_reason = ""
        self.warnings: list[str] = []
        #: How far each joint has been outside its range at best so far [rad].
        self._outside: dict[str, FloatArray] = {}

    # -- the samples ------------------------------------------------------------------
    def _fail(self, criterion: str, message: str, amount: float = math.nan,
              limit: float = math.nan) -> None:
        k = max(self.rows - 1, 0)
        t = self.path_start + k * self.dt
        self.failure = Failure(criterion, k, t, amount, limit,
                               f"step {k} at t = {t:.4f} s: {message}")

    def _checked(self, reading: Reading) -> bool:
        """Whether ``reading`` may be acted on (else the failure is set).

        Not when it is older than the watchdog allows, nor when a joint is further
        outside its range than it has been since the start (by more than the margin: a
        start outside a range, which the step's recovery brings back, is allowed).
        """
        age = self.cell.now() - reading.t
        if age > self.settings.watchdog:
            self._fail("watchdog", f"the newest state is {age:.4g} s old (watchdog "
                       f"{self.settings.watchdog:g} s): the robots' state stopped coming",
                       age, self.settings.watchdog)
            return False
        margin = self.settings.range_margin
        for role, arm, q in (("leader", self.task.leader, reading.q_l),
                             ("follower", self.task.follower, reading.q_f)):
            out = np.maximum(np.maximum(arm.q_min - q, q - arm.q_max), 0.0)
            allowed = self._outside.setdefault(role, out)  # the start's (outside it may be)
            j = int(np.argmax(out - allowed))
            if out[j] > allowed[j] + margin:
                self._fail("range", f"the {role}'s joint {j + 1} is measured at {q[j]:.6g} "
                           f"rad, {out[j]:.3g} rad outside its range [{arm.q_min[j]:.6g}, "
                           f"{arm.q_max[j]:.6g}], further out than it has been (margin "
                           f"{margin:g} rad)", float(out[j]), float(allowed[j] + margin))
                return False
            self._outside[role] = np.minimum(allowed, out)
        return True

    def _log_row(self, reading: Reading, sent: FloatArray, computed: FloatArray,
                 state: DualArmState) -> None:
        lg = self.log
        lg.robot_t.append(reading.t)
        lg.age.append(self.cell.now() - reading.t)
        lg.sent.append(sent.copy())
        lg.computed.append(computed.copy())
        lg.sigma_measured.append(reading.sigma)
        lg.offset.append(float(np.max(np.abs(np.r_[reading.q_l - state.q_l,
                                                   reading.q_f - state.q_f]), initial=0.0)))

    def _observe(self, k: int) -> None:
        """Hand row ``k`` to the observer, once the row is counted.

        An interrupt inside the observer (Ctrl-C while it publishes) then leaves the
        record whole.
        """
        if self.observer is not None:
            self.observer(self.trace, k)

    def _sample_failure(self, k: int, out: ControlOutput) -> None:
        tr, lim = self.trace, self.limits
        for criterion, what, pos, rot, (tp, tr_) in (
                ("closure", "grasp closure lost", tr.closure_pos_err[k], tr.closure_rot_err[k],
                 lim.closure),
                ("tracking", "leader left its path", tr.leader_pos_err[k], tr.leader_rot_err[k],
                 lim.tracking)):
            if pos > tp or rot > tr_:
                self._fail(criterion, f"{what}: {pos:.3g} m, {rot:.3g} rad (tolerance {tp:g} m, "
                           f"{tr_:g} rad)", float(pos), tp)
                return
        if not out.applied:
            self._fail("solver", f"solver status {out.status.value}: {out.solution.message}")

    def run(self, progress: Callable[[float, float], None] | None) -> None:
        """Run the samples until the path's end or a stop (the failure says which)."""
        cell, dt, task = self.cell, self.dt, self.task
        first = cell.open()
        self.t0 = first.t
        init = self.initial
        off = float(np.max(np.abs(np.r_[first.q_l - init.q_l, first.q_f - init.q_f])))
        if off > self.settings.start_tolerance:
            self._fail("start", f"the robots are not at the file's start: a joint is "
                       f"{off:.4g} rad from it (start_tolerance "
                       f"{self.settings.start_tolerance:g} rad); move them there first",
                       off, self.settings.start_tolerance)
            return
        self.controller.reset()
        tau = self.path_start
        model = DualArmState(tau, first.q_l.copy(), first.q_f.copy(),
                             estimate_grasp(task, first.q_l, first.q_f).sigma)
        end_tol = 1e-9 * max(1.0, abs(self.path_end))
        for k in range(self.max_rows):
            reading = first if k == 0 else cell.read()
            if not self._checked(reading):
                return
            est = estimate_grasp(task, reading.q_l, reading.q_f)
            state = (DualArmState(tau, model.q_l, model.q_f, model.sigma)
                     if self.settings.dry_run
                     else DualArmState(tau, reading.q_l, reading.q_f, est.sigma))
            at_end = tau >= self.path_end - end_tol
            scale_max = 0.0 if at_end else min(1.0, (self.path_end - tau) / dt)
            t_k = self.path_start + k * dt
            try:
                out = self.controller.step(state, scale_max=scale_max)
            except DualArmError as err:
                record_state(self.trace, k, t_k, state, self.controller,
                             "infeasible" if isinstance(err, InfeasibleStepError) else "error")
                self._log_row(reading, self.sent1, np.zeros_like(self.sent1), state)
                self.rows = self.control_rows = k + 1
                self._observe(k)
                self._fail("solver", str(err))
                return
            computed = (np.r_[out.ql_dot, out.qf_dot] if out.applied and not at_end
                        else np.zeros_like(self.sent1))
            sent = self.lim.clamp(computed, self.sent1, self.sent2)
            if at_end:  # the path is done: the stop ramp brings the arms to rest
                sent = self.sent1.copy()
            record(self.trace, k, t_k, state, out, self.controller)
            if at_end and k:
                self.trace.scale[k] = self.trace.scale[k - 1]
            self._log_row(reading, sent, computed, state)
            self.rows = self.control_rows = k + 1
            self._observe(k)
            self._sample_failure(k, out)
            if self.failure is not None or at_end:
                return
            if not self.settings.dry_run:
                cell.send(sent[:self.n_l], sent[self.n_l:])
            self.sent2, self.sent1 = self.sent1, sent
            if progress is not None:
                progress(min((tau - self.path_start) / (self.path_end - self.path_start), 1.0),
                         0.0)
            model = state.advanced(_Sent(sent[:self.n_l], sent[self.n_l:], out.m,
                                         out.m_leader, out.scale), dt)
            tau = tau + dt * out.scale
            cell.wait_until(self.t0 + (k + 1) * dt)
        self._fail("path_incomplete", "path not completed within the duration cap")

    # -- the stop ---------------------------------------------------------------------
    def stop(self) -> None:
        """Bring both arms to rest from the last command sent, recording each sample."""
        ramp = StopRamp(self.lim, self.sent1, self.sent2)
        if self.rows == 0 or ramp.at_rest:
            return
        cell, dt = self.cell, self.dt
        with SignalHold():
            try:
                while not ramp.at_rest:
                    v = ramp.next()
                    if not self.settings.dry_run:
                        cell.send(v[:self.n_l], v[self.n_l:])
                    k = self.rows
                    cell.wait_until(self.t0 + k * dt)
                    reading = cell.read()
                    state = DualArmState(float(self.trace.tau[k - 1]), reading.q_l, reading.q_f,
                                         float(self.trace.grasp[k - 1]))
                    if k >= len(self.trace):
                        break
                    record_state(self.trace, k, self.path_start + k * dt, state,
                                 self.controller, "stopping")
                    self.trace.ql_dot[k], self.trace.qf_dot[k] = v[:self.n_l], v[self.n_l:]
                    self._log_row(reading, v, v, state)
                    self.rows = k + 1
                    self.sent2, self.sent1 = self.sent1, v
                    self._observe(k)
            except CellError as err:
                self.warnings.append(f"the stop could not be completed: {err}")


def drive(cell: Cell, controller: DualArmController, initial: DualArmState, *,
          duration: float, settings: DriveSettings, limits: RunLimits | None = None,
          progress: Callable[[float, float], None] | None = None,
          observer: Observer | None = None) -> DriveResult:
    """Drive ``cell`` along ``duration`` seconds of path (see the module).

    Parameters
    ----------
    cell : Cell
        The two arms.
    controller : DualArmController
        The per-step controller.
    initial : DualArmState
        The file's start: the path time and the joints the robots must be at.
    duration : float
        Length of the path [s].
    settings : DriveSettings
        Watchdog, dry run, start tolerance, range margin.
    limits : RunLimits, optional
        Tolerances and cap (defaults: :class:`~dualarm_qp.control.run_limits.RunLimits`).
    progress : callable, optional
        Called as ``progress(path_done, 0.0)`` after every sample.
    observer : callable, optional
        Called as ``observer(trace, k)`` with each row just recorded (:data:`Observer`).

    Returns
    -------
    DriveResult
        Never raises for a stop: Ctrl-C (SIGINT), SIGTERM, the watchdog, a cell error or
        a failed step end the samples, the arms are brought to rest, and the result says
        why, with every sample recorded.
    """
    limits = RunLimits() if limits is None else limits
    loop = _Loop(cell, controller, initial, duration, settings, limits, observer)
    try:
        try:
            loop.run(progress)
        except KeyboardInterrupt as exc:
            loop._fail("interrupted", f"interrupted ({str(exc) or 'KeyboardInterrupt'}) after "
                       f"{loop.rows} samples")
        except CellError as err:
            loop._fail("cell", str(err))
        loop.stop()
    finally:
        try:
            cell.close()
        except CellError as err:
            loop.warnings.append(f"closing the cell: {err}")
    return _result(loop)


def _result(loop: _Loop) -> DriveResult:
    """Assemble the run's result from the loop's record."""
    controller = loop.controller
    trace = loop.trace.truncate(loop.rows)
    record_margins(trace, loop.task)
    control = trace.truncate(loop.control_rows)
    realised = cell_realised(controller, control, loop.dt)
    failure = loop.failure
    if failure is None and controller.hard_bounds:
        breaches = [r.breach for r in realised.values() if r.breach is not None]
        if breaches:
            b = min(breaches, key=lambda b: b.sample)
            t = float(control.t[b.sample])
            failure = Failure(b.criterion, b.sample, t, b.amount, b.limit,
                              f"step {b.sample} at t = {t:.4f} s: the measured motion broke a "
                              f"limit: {b.describe(loop.dt)}")
    result = RolloutResult(trace, failure, controller.solver.name, loop.dt, loop.path_start,
                           loop.path_end, realised, controller.hard_bounds,
                           warnings=loop.warnings,
                           extras={"closure_tolerance_m_rad": list(loop.limits.closure),
                                   "tracking_tolerance_m_rad": list(loop.limits.tracking)})
    lg = loop.log
    columns = cell_columns(lg.robot_t, lg.age, lg.sent, lg.computed, lg.sigma_measured,
                           loop.n_l, offset=lg.offset if loop.settings.dry_run else None)
    cell = {"kind": loop.cell.kind, "between": loop.cell.between,
            "dry_run": loop.settings.dry_run, "watchdog_s": loop.settings.watchdog,
            "control_samples": loop.control_rows,
            "state_age_max_s": float(max(lg.age[:loop.control_rows], default=math.nan)),
            "clamped_max_rad_s": float(max((float(np.max(np.abs(s - c), initial=0.0))
                                            for s, c in zip(lg.sent[:loop.control_rows],
                                                            lg.computed[:loop.control_rows],
                                                            strict=True)), default=0.0)),
            "clock_jitter_max_s": float(max(
                (abs(t - loop.t0 - k * loop.dt) for k, t in enumerate(lg.robot_t)),
                default=0.0)),
            "stop": stop_summary(loop.lim, lg.sent, loop.control_rows,
                                 loop.failure.criterion if loop.failure else "end")}
    return DriveResult(result, columns, cell)


__all__ = ["DriveResult", "DriveSettings", "Observer", "command_limits", "drive"]
