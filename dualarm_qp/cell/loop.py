"""The drive loop: one loop for every cell (MuJoCo, ROS 2, Franka), on the cell's clock.

Each sample ``k``, at the cell's time ``t0 + k dt``:

1. **wait** for the cell's clock to reach it, and **read** both arms' measured joints
   (:meth:`Cell.read <.base.Cell.read>`); a state older than ``watchdog`` on the
   cell's clock, or a joint outside its range by more than ``range_margin``, stops
   the cell;
2. **estimate the grasp** from the two arms' joints (:mod:`.grasp`);
3. **step** the controller from that state (in a dry run: from the model's state,
   integrated from the measured start as ``run`` does);
4. **clamp** the command to the joints' speed, acceleration and jerk limits
   (:mod:`.safety`), **record** the sample (the columns of ``run``'s
   ``trajectory.csv`` and the cell's own, :mod:`.record`) and **send** the command
   (not in a dry run).

SIGINT and SIGTERM are held while the loop runs and acted on between two samples, so
every recorded sample is whole and its command was sent. Whatever ends the loop (the
path's end, a failed step, a signal, the watchdog, a state out of range, a cell error),
both arms are then brought to rest by the stop ramp (:class:`~.safety.StopRamp`),
whose commands keep the sample grid and are recorded too (status ``stopping``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from .._signals import Interrupted, SignalHold, signal_name
from ..control.controller import ControlOutput, DualArmController
from ..control.rollout import Failure, RolloutResult, RunLimits
from ..control.trace import Trace, record, record_margins, record_state
from ..errors import DualArmError, InfeasibleStepError
from ..step.state import DualArmState
from ..task.scene import DualArmTask
from .base import Cell, CellError, Reading
from .grasp import estimate_grasp
from .record import cell_columns, cell_realised, stop_summary
from .safety import StopRamp, command_limits, stop_samples_bound
from .settings import DriveResult, DriveSettings

FloatArray = NDArray[np.float64]

#: Called with the trace and the row just recorded (control and stop rows alike); it
#: must not raise (an observer that can fail keeps its own errors).
Observer = Callable[[Trace, int], None]


@dataclass
class _Log:
    """The cell's own values per row (the rest goes into the :class:`Trace`)."""

    robot_t: list[float] = field(default_factory=list)
    age: list[float] = field(default_factory=list)
    sent: list[FloatArray] = field(default_factory=list)
    computed: list[FloatArray] = field(default_factory=list)
    sigma_measured: list[float] = field(default_factory=list)
    offset: list[float] = field(default_factory=list)
    late: list[float] = field(default_factory=list)


@dataclass(frozen=True)
class _Sent:
    """The rates sent, as a command the model integrates (a dry run's state)."""

    ql_dot: FloatArray
    qf_dot: FloatArray
    m: float
    m_leader: float
    scale: float


class _Loop:
    """One drive of a cell (see the module); :func:`drive` runs it."""

    def __init__(self, cell: Cell, controller: DualArmController, initial: DualArmState,
                 duration: float, settings: DriveSettings, limits: RunLimits,
                 judged_by: DualArmTask | None = None,
                 observer: Observer | None = None) -> None:
        self.cell, self.controller, self.settings, self.limits = cell, controller, settings, limits
        self.observer = observer
        self.task = controller.task
        self.judged_by = controller.task if judged_by is None else judged_by
        self.dt = controller.options.dt
        self.initial = initial
        self.path_start = float(initial.t)
        self.path_end = self.path_start + duration
        cap = 2.0 * duration if limits.duration_cap is None else limits.duration_cap
        self.max_rows = math.floor(cap / self.dt + 1e-9) + 1
        self.lim = command_limits(controller)
        n_l, n_f = self.task.leader.n, self.task.follower.n
        self.n_l = n_l
        self.trace = Trace.allocate(self.max_rows + stop_samples_bound(self.lim), n_l, n_f)
        self.log = _Log()
        self.rows = 0
        self.control_rows = 0
        #: Rows whose command was sent (the next command goes with row ``sent_rows``).
        self.sent_rows = 0
        #: The first row whose command is the stop's.
        self.stop_first = 0
        self.signals: SignalHold | None = None
        self.tau = self.path_start
        self.model = initial
        self.sent1 = np.zeros(n_l + n_f)
        self.sent2 = np.zeros(n_l + n_f)
        self.t0 = 0.0
        self.failure: Failure | None = None
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
        lg.late.append(reading.late)
        lg.offset.append(float(np.max(np.abs(np.r_[reading.q_l - state.q_l,
                                                   reading.q_f - state.q_f]), initial=0.0)))

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

    def _send(self, v: FloatArray) -> None:
        """Send ``v`` to both arms (not in a dry run); it becomes the last command."""
        if not self.settings.dry_run:
            self.cell.send(v[:self.n_l], v[self.n_l:])
        self.sent2, self.sent1 = self.sent1, v
        self.sent_rows = self.rows

    def _at_start(self, first: Reading) -> bool:
        """Whether the robots are at the file's start (else the failure is set)."""
        init = self.initial
        off = float(np.max(np.abs(np.r_[first.q_l - init.q_l, first.q_f - init.q_f])))
        if off > self.settings.start_tolerance:
            self._fail("start", f"the robots are not at the file's start: a joint is "
                       f"{off:.4g} rad from it (start_tolerance "
                       f"{self.settings.start_tolerance:g} rad); move them there first",
                       off, self.settings.start_tolerance)
            return False
        return True

    def _sample(self, k: int, reading: Reading) -> bool:
        """Do sample ``k`` from ``reading`` (see the module); return whether to go on.

        The row's command is sent only when the loop goes on: at the path's end or a
        failed step, the stop's first command goes out with this row (:meth:`stop`).
        """
        if not self._checked(reading):
            return False
        dt, tau, model = self.dt, self.tau, self.model
        est = estimate_grasp(self.task, reading.q_l, reading.q_f)
        state = (DualArmState(tau, model.q_l, model.q_f, model.sigma) if self.settings.dry_run
                 else DualArmState(tau, reading.q_l, reading.q_f, est.sigma))
        at_end = tau >= self.path_end - 1e-9 * max(1.0, abs(self.path_end))
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
            return False
        computed = (np.r_[out.ql_dot, out.qf_dot] if out.applied and not at_end
                    else np.zeros_like(self.sent1))
        sent = self.sent1.copy() if at_end else self.lim.clamp(computed, self.sent1, self.sent2)
        record(self.trace, k, t_k, state, out, self.controller)
        if at_end and k:
            self.trace.scale[k] = self.trace.scale[k - 1]
        self._log_row(reading, sent, computed, state)
        self.rows = self.control_rows = k + 1
        self._observe(k)
        self._sample_failure(k, out)
        if self.failure is not None or at_end:
            return False
        self._send(sent)
        self.model = state.advanced(_Sent(sent[:self.n_l], sent[self.n_l:], out.m,
                                          out.m_leader, out.scale), dt)
        self.tau = tau + dt * out.scale
        return True

    def run(self, progress: Callable[[float, float], None] | None) -> None:
        """Run the samples until the path's end or a stop (the failure says which).

        A signal held by ``self.signals`` stops the loop after the sample it came in
        (raised as :class:`~dualarm_qp._signals.Interrupted`): every sample is whole.
        """
        first = self.cell.open()
        self.t0 = first.t
        if not self._at_start(first):
            return
        self.controller.reset()
        self.tau = self.path_start
        self.model = DualArmState(self.tau, first.q_l.copy(), first.q_f.copy(),
                                  estimate_grasp(self.task, first.q_l, first.q_f).sigma)
        span = self.path_end - self.path_start
        for k in range(self.max_rows):
            if k:
                self.cell.wait_until(self.t0 + k * self.dt)
            if not self._sample(k, first if k == 0 else self.cell.read()):
                return
            if self.signals is not None and self.signals.signum is not None:
                raise Interrupted(self.signals.signum)
            if progress is not None:
                progress(min((self.tau - self.path_start) / span, 1.0), 0.0)
        self._fail("path_incomplete", "path not completed within the duration cap")

    # -- the stop ---------------------------------------------------------------------
    def _stop_row(self, k: int, reading: Reading, v: FloatArray) -> None:
        """Record stop sample ``k``: the state read then and the command sent with it."""
        est = estimate_grasp(self.task, reading.q_l, reading.q_f)
        state = DualArmState(float(self.trace.tau[k - 1]), reading.q_l, reading.q_f,
                             est.sigma)
        record_state(self.trace, k, self.path_start + k * self.dt, state, self.controller,
                     "stopping")
        self.trace.ql_dot[k], self.trace.qf_dot[k] = v[:self.n_l], v[self.n_l:]
        self._log_row(reading, v, v, state)
        self.rows = k + 1
        self._observe(k)

    def _observe(self, k: int) -> None:
        """Hand row ``k`` to the observer, once the row is counted (a whole record)."""
        if self.observer is not None:
            self.observer(self.trace, k)

    def stop(self) -> None:
        """Bring both arms to rest from the last command sent, recording each sample.

        The stop's commands keep the sample grid: the first goes out one sample after the
        last command sent (with the last row, when that row's own command was not sent:
        the path's end, a failed step), then one each sample, each recorded with the
        state read at its sample (status ``stopping``).
        """
        ramp = StopRamp(self.lim, self.sent1, self.sent2)
        self.stop_first = k = self.sent_rows
        if ramp.at_rest:
            return
        try:
            if self.rows > k:  # this sample's row is recorded; its command is the stop's
                v = ramp.next()
                self.log.sent[k] = v
                self._send(v)
                k += 1
            while not ramp.at_rest and k < len(self.trace):
                self.cell.wait_until(self.t0 + k * self.dt)
                reading = self.cell.read()
                v = ramp.next()
                self._stop_row(k, reading, v)
                self._send(v)
                k += 1
        except CellError as err:
            self.warnings.append(f"the stop could not be completed: {err}")
            return
        if not ramp.at_rest:
            self.warnings.append(f"the stop did not reach rest within {k - self.stop_first} "
                                 "samples")


def drive(cell: Cell, controller: DualArmController, initial: DualArmState, *,
          duration: float, settings: DriveSettings, limits: RunLimits | None = None,
          progress: Callable[[float, float], None] | None = None,
          judged_by: DualArmTask | None = None,
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
        Tolerances and cap (defaults: :class:`~dualarm_qp.control.rollout.RunLimits`).
    progress : callable, optional
        Called as ``progress(path_done, 0.0)`` after every sample.
    judged_by : DualArmTask, optional
        The task whose joint limits the recorded motion is measured against (default
        the controller's; ``drive`` passes the file's while its controller commands
        within ``1 - cell.headroom`` of them).
    observer : callable, optional
        Called as ``observer(trace, k)`` with each row just recorded, control and stop
        rows alike (:data:`Observer`: a live view, the ROS 2 node's topics).

    Returns
    -------
    DriveResult
        Never raises for a stop: SIGINT or SIGTERM (held while the loop runs, and
        acted on between two samples), a KeyboardInterrupt, the watchdog, a cell error
        or a failed step end the samples, the arms are brought to rest, and the result
        says why, with every sample recorded. Any other error (bad input) is raised
        once the arms are at rest.
    """
    limits = RunLimits() if limits is None else limits
    error: BaseException | None = None
    with SignalHold(deliver=False) as signals:
        loop = _Loop(cell, controller, initial, duration, settings, limits, judged_by, observer)
        loop.signals = signals
        try:
            loop.run(progress)
        except KeyboardInterrupt as exc:
            if loop.failure is None:
                loop._fail("interrupted", f"interrupted ({str(exc) or 'KeyboardInterrupt'}) "
                           f"after {loop.rows} samples")
        except CellError as err:
            loop._fail("cell", str(err))
        except BaseException as exc:  # bad input (or a bug): stop the arms, then raise
            error = exc
        if error is None and signals.signum is not None:  # it came in the last sample
            if loop.failure is None:
                loop._fail("interrupted", f"interrupted ({signal_name(signals.signum)}) "
                           f"after {loop.rows} samples")
            signals.signum = None
        loop.stop()
        try:
            cell.close()
        except CellError as err:
            loop.warnings.append(f"closing the cell: {err}")
        if error is not None:
            raise error
        if signals.signum is not None:
            loop.warnings.append(f"{signal_name(signals.signum)} came while the arms were "
                                 "brought to rest; the stop was completed")
        return _result(loop)


def _result(loop: _Loop) -> DriveResult:
    """Assemble the run's result from the loop's record."""
    controller = loop.controller
    trace = loop.trace.truncate(loop.rows)
    record_margins(trace, loop.task)
    control = trace.truncate(loop.control_rows)
    times = np.asarray(loop.log.robot_t[:loop.control_rows], dtype=np.float64)
    realised = cell_realised(loop.judged_by, controller.options, control, times)
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
                           loop.n_l, late=lg.late,
                           offset=lg.offset if loop.settings.dry_run else None)
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
            "stop": stop_summary(loop.lim, lg.sent, loop.stop_first,
                                 loop.failure.criterion if loop.failure else "end")}
    return DriveResult(result, columns, cell)


__all__ = ["DriveResult", "DriveSettings", "Observer", "command_limits", "drive"]
