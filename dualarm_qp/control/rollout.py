"""The rollout: integrate the controller along the path, record it, and judge the run.

A run **completes** only when the task was done:

* the whole path was executed (path time at its end; under the ``"scale"`` policy the
  run goes on past the nominal duration, up to ``duration_cap``);
* the leader tracked ``D(t)`` and the grasp closure held, within their tolerances;
* for a solver that claims hard limits, the realised motion (:mod:`.realised`) kept
  every limit of both arms and of the grasp.

Otherwise it **fails**, and :class:`Failure` names the criterion, the sample and the
amount. Every sample is kept either way.
"""

from __future__ import annotations

import dataclasses
import math
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from ..collision.clearance import ClearanceReport
from ..errors import DualArmError, InfeasibleStepError, InvalidInputError, SupportLostError
from ..kinematics.arm import SerialArm
from ..kinematics.ik import ik_dls
from ..solvers._affine import factor
from ..step.state import DualArmState
from .collisions import blocked_by_pair, clearance_at_start, path_collision_of, record_clearance
from .conflicts import plainly
from .controller import DualArmController
from .loads import record_loads
from .plant import Plant, not_followed, planned_errors
from .preflight import REACH_TOLERANCE, unreachable_waypoint
from .realised import LimitReport, measure
from .torques import TorqueReport, blocked_by_torque, record_torques, torque_at_start
from .trace import Trace, record, record_margins, record_state

FloatArray = NDArray[np.float64]

#: Criteria a run can fail on (``Failure.criterion``).
CRITERIA = ("unreachable", "path_collision", "solver", "support", "closure", "tracking",
            "singularity", "stalled", "path_incomplete",
            "range", "speed", "acceleration", "jerk", "collision", "torque", "interrupted",
            "watchdog", "start", "cell")  # the last three: a drive's (docs/robots.md)

#: Criteria whose failure message names its cause (:mod:`.diagnosis`).
EXPLAINED = ("closure", "tracking", "stalled", "path_incomplete")

#: What a smallest singular value below the threshold does.
SINGULARITY_ACTIONS = ("warn", "stop", "ignore")


@dataclass(frozen=True)
class Failure:
    """Why a run failed.

    Attributes
    ----------
    criterion : str
        One of :data:`CRITERIA`.
    sample : int
        Row of the trace where it was found.
    t : float
        Time of that sample [s].
    amount : float
        The offending value (an error [m or rad], a ratio, a singular value, a share of
        the path); NaN when there is none (a solver message).
    limit : float
        What it was allowed.
    message : str
        One line for a person.
    """

    criterion: str
    sample: int
    t: float
    amount: float
    limit: float
    message: str

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready."""
        return {"criterion": self.criterion, "sample": self.sample, "t_s": self.t,
                "amount": self.amount, "limit": self.limit, "message": self.message}


@dataclass(frozen=True)
class RunLimits:
    """What a run must keep to complete, and how far it may run.

    Parameters
    ----------
    closure : tuple of float
        ``(position [m], rotation [rad])`` of the grasp closure error (default 1 mm,
        0.01 rad): beyond it the object would be torn or dropped.
    tracking : tuple of float
        ``(position [m], rotation [rad])`` of the leader's error to ``D(path time)``
        (default 1 mm, 0.01 rad).
    singular_value_min : float
        Threshold on the smallest singular value of either arm's Jacobian (default
        1e-3; 0 turns it off).
    singularity_action : {"warn", "stop", "ignore"}
        What a sample below the threshold does (default ``"warn"``).
    stall_time : float
        A run whose path time advances by less than 1% of the time elapsed over a
        window of this length [s] fails as stalled (default 1 s).
    duration_cap : float, optional
        Longest run [s] when the task was slowed; default twice the duration.
    """

    closure: tuple[float, float] = (1e-3, 1e-2)
    tracking: tuple[float, float] = (1e-3, 1e-2)
    singular_value_min: float = 1e-3
    singularity_action: str = "warn"
    stall_time: float = 1.0
    duration_cap: float | None = None

    def __post_init__(self) -> None:
        for name in ("closure", "tracking"):
            pos, rot = getattr(self, name)
            if not (pos > 0 and rot > 0):
                raise InvalidInputError(f"{name} tolerance must be positive, got "
                                        f"{getattr(self, name)}")
        if not (math.isfinite(self.singular_value_min) and self.singular_value_min >= 0):
            raise InvalidInputError("singular_value_min must be a finite number >= 0")
        if self.singularity_action not in SINGULARITY_ACTIONS:
            raise InvalidInputError(f"singularity_action must be one of "
                                    f"{SINGULARITY_ACTIONS}, got {self.singularity_action!r}")
        if not self.stall_time > 0:
            raise InvalidInputError("stall_time must be positive")


@dataclass
class RolloutResult:
    """Outcome of a rollout.

    Attributes
    ----------
    trace : Trace
        The samples that were completed.
    failure : Failure or None
        Why the run failed; None when it completed.
    solver : str
        Solver name.
    dt : float
        Sampling interval [s].
    path_start, path_end : float
        Path time of the start and of the end of the task [s].
    realised : dict of str to LimitReport
        The realised motion against the limits of ``"leader"``, ``"follower"`` and
        ``"grasp"``.
    hard_bounds : bool
        Whether the solver claims hard limits (then the realised limits decide
        completion).
    warnings : list of str
        What a person should know although the run may have completed.
    extras : dict
        Further settings to report.
    clearance : ClearanceReport or None
        The recorded motion's smallest clearance (a task with a collision scene).
    torque : TorqueReport or None
        The recorded motion's joint torques against their limits (a task with a load,
        or torque limits).
    """

    trace: Trace
    failure: Failure | None
    solver: str
    dt: float
    path_start: float
    path_end: float
    realised: dict[str, LimitReport]
    hard_bounds: bool
    warnings: list[str] = field(default_factory=list)
    extras: dict[str, Any] = field(default_factory=dict)
    clearance: ClearanceReport | None = None
    torque: TorqueReport | None = None

    @property
    def completed(self) -> bool:
        """Whether the task was done (see the module docstring)."""
        return self.failure is None

    @property
    def message(self) -> str:
        """Why the run failed ("" when it completed)."""
        return "" if self.failure is None else self.failure.message

    @property
    def time_lost(self) -> float:
        """Time the run took beyond what the executed path needs at full speed [s].

        The elapsed time minus the whole samples that the path time advanced would
        take unscaled (the last sample's shortening where the path ends is no loss).
        """
        tr = self.trace
        if not len(tr):
            return 0.0
        return _time_lost(float(tr.t[-1] - tr.t[0]), float(tr.tau[-1] - tr.tau[0]), self.dt)

    @property
    def path_completed(self) -> float:
        """Share of the path executed, in [0, 1]."""
        tr = self.trace
        if not len(tr):
            return 0.0
        span = self.path_end - self.path_start
        return float(min(max((tr.tau[-1] - self.path_start) / span, 0.0), 1.0))

    def summary(self) -> dict[str, Any]:
        """Scalars that sum the run up (JSON-ready)."""
        tr = self.trace
        n = len(tr)

        def fmax(a: FloatArray) -> float:
            return float(np.nanmax(a)) if a.size and not np.all(np.isnan(a)) else float("nan")

        def fmin(a: FloatArray) -> float:
            return float(np.nanmin(a)) if a.size and not np.all(np.isnan(a)) else float("nan")

        solve = tr.solve_time_s[~np.isnan(tr.solve_time_s)]
        step = tr.step_time_s[~np.isnan(tr.step_time_s)]
        out: dict[str, Any] = {
            "solver": self.solver,
            "completed": self.completed,
            "message": self.message,
            "failure": None if self.failure is None else self.failure.as_dict(),
            "warnings": list(self.warnings),
            "samples": n,
            "dt_s": self.dt,
            "t_end_s": float(tr.t[-1]) if n else 0.0,
            "path_time_end_s": float(tr.tau[-1]) if n else 0.0,
            "path_completed_pct": 100.0 * self.path_completed,
            "time_lost_to_scaling_s": self.time_lost,
            "status_counts": dict(sorted(Counter(tr.status).items())),
            "fallback_steps": int(np.nansum(tr.fallback)),
            "hard_limits": self.hard_bounds,
            "realised_limits": {k: v.as_dict() for k, v in self.realised.items()},
            "closure_pos_err_max_m": fmax(tr.closure_pos_err),
            "closure_rot_err_max_rad": fmax(tr.closure_rot_err),
            "closure_pos_err_pre_max_m": fmax(tr.closure_pos_err_pre),
            "closure_rot_err_pre_max_rad": fmax(tr.closure_rot_err_pre),
            "correction_max_rad": {"leader": fmax(tr.correction_l),
                                   "follower": fmax(tr.correction_f)},
            "leader_pos_err_max_m": fmax(tr.leader_pos_err),
            "leader_rot_err_max_rad": fmax(tr.leader_rot_err),
            "sigma_min": {"leader": fmin(tr.sigma_min_l), "follower": fmin(tr.sigma_min_f)},
            "grasp_start_m": float(tr.grasp[0]) if n else float("nan"),
            "grasp_end_m": float(tr.grasp[-1]) if n else float("nan"),
            "grasp_min_m": fmin(tr.grasp),
            "grasp_max_m": fmax(tr.grasp),
            "grasp_leader_start_m": float(tr.grasp_leader[0]) if n else float("nan"),
            "grasp_leader_end_m": float(tr.grasp_leader[-1]) if n else float("nan"),
            "margin_qf_min_rad": fmin(tr.margin_qf),
            "margin_qf_start_rad": fmin(tr.margin_qf[:1]),
            "margin_qf_min_after_start_rad": fmin(tr.margin_qf[1:]),
            "margin_qf_min_per_joint_rad": [fmin(tr.margin_qf[:, j])
                                            for j in range(tr.margin_qf.shape[1])],
            "margin_ql_min_rad": fmin(tr.margin_ql),
            "margin_grasp_min_m": fmin(tr.margin_grasp),
            "end_inside_all_ranges": bool(
                n and np.nanmin(tr.margin_qf[-1]) >= -1e-9
                and np.nanmin(tr.margin_ql[-1]) >= -1e-9 and tr.margin_grasp[-1] >= -1e-9
                and not tr.margin_grasp_leader[-1] < -1e-9
            ),
            "bound_violation_max": fmax(tr.bound_violation),
            "eq_residual_max": fmax(tr.eq_residual),
            "solve_time_median_s": float(np.median(solve)) if solve.size else float("nan"),
            "solve_time_p99_s": float(np.percentile(solve, 99)) if solve.size else float("nan"),
            "step_time_median_s": float(np.median(step)) if step.size else float("nan"),
            "step_time_p99_s": float(np.percentile(step, 99)) if step.size else float("nan"),
        }
        if self.clearance is not None:
            out["realised_limits"]["clearance"] = self.clearance.as_dict()
        if self.torque is not None:
            out["realised_limits"]["torque"] = self.torque.as_dict()
        out.update(self.extras)
        return out


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

    Each sample: the controller computes the command from the current state; the
    leader integrates ``ql_dot * dt``, the follower ``qf_dot * dt`` and the grasp
    ``m * dt``; the path time advances by ``scale * dt`` (a scaled step slows the
    object). The run ends when the path time reaches ``initial.t + duration``; a
    slowed task runs longer, up to ``limits.duration_cap``.

    Drift correction: Euler integration leaves a closure and tracking error of second
    order in ``dt`` per step, which the controller's feedback terms remove over the
    following steps, inside the step's limits. The paper's methods, which ignore
    limits, may also use position-level corrections after the step: the Sec. 3.3
    re-resolution of the hand orientation on a curved path (``reresolve_orientation``)
    and a drift projection (``project``: a few Gauss-Newton iterations putting the
    leader on ``D(path time) H1^-1`` and the follower on the grasp). Their effect is
    recorded (``closure_*_err_pre``, ``correction_*``). A solver that claims hard
    limits refuses both: an unbounded correction after the step would break them.

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
    reresolve_orientation : bool, optional
        Apply the Sec. 3.3 re-resolution; default: for the paper's methods, when the
        path is curved and the controller freezes the orientation.
    project : bool, optional
        Apply the drift projection; default: for the paper's methods.
    progress : callable, optional
        Called as ``progress(path_done, time_lost)`` after every sample: the share of
        the path executed, in [0, 1] (1 at the last sample of a completed run, however
        long the slowed task took), and the time lost to slowing so far [s] (as
        :attr:`RolloutResult.time_lost`). It may raise KeyboardInterrupt to stop the run.
    stop_on_interrupt : bool
        On KeyboardInterrupt (Ctrl-C) during the samples, stop and return the samples
        completed so far, failing on criterion ``"interrupted"``; by default the
        exception propagates (and the samples are lost).
    preflight : bool
        Before the first sample, check that both arms can reach the path at its
        waypoints (:mod:`.preflight`; criterion ``"unreachable"``), that no joint needs
        more than its torque limit at the start (with torque limits; ``"torque"``), that
        no collision pair is closer than the safety distance less the allowance at the
        start and that ``D(t)`` keeps the object off the obstacles (with collision
        avoidance; ``"collision"``, ``"path_collision"``): a check that fails fails the
        run with no sample run. Default True.
    initial_rates : ndarray, optional
        The rates the pair moves at when the run starts [rad/s, m/s], in the
        controller's decision order (:attr:`DualArmController.layout`); default zero (the
        run starts at rest). Acceleration limits and their realised check start from it.
    plant : Plant, optional
        What the commands drive (:mod:`.plant`): each sample's state is then the one the
        plant measured (default: the command integrated exactly). With a plant the
        position-level corrections are off by default (they would move a state that is
        measured, not commanded).

    Returns
    -------
    RolloutResult
        Never raises for a failed step: the run stops, and the result says why while
        keeping every completed sample.

    Raises
    ------
    InvalidInputError
        A non-positive duration, a cap below it, or a position-level correction asked
        for a solver that claims hard limits.
    """
    if not (math.isfinite(duration) and duration > 0):
        raise InvalidInputError(f"duration must be a positive number of seconds, got {duration}")
    limits = RunLimits() if limits is None else limits
    cap = 2.0 * duration if limits.duration_cap is None else limits.duration_cap
    if not cap >= duration:
        raise InvalidInputError(f"duration_cap ({cap:g} s) must be at least the duration "
                                f"({duration:g} s)")
    task = controller.task
    leader, follower, surface = task.leader, task.follower, task.surface
    hard = controller.hard_bounds
    curved = bool(getattr(surface, "curved", False)) or float(
        np.linalg.norm(surface.angular_rate(float(initial.sigma)))) > 0.0
    if reresolve_orientation is None:
        reresolve_orientation = (not hard and curved and plant is None
                                 and not controller.options.exact_orientation)
    if project is None:
        project = not hard and plant is None
    if hard and (project or reresolve_orientation):
        raise InvalidInputError(
            f"solver '{controller.solver.name}' keeps hard limits: the position-level "
            "corrections (projection, re-resolution) are unbounded and would break them; "
            "its drift is corrected through the step's feedback term")
    dt = controller.options.dt
    path_start = float(initial.t)
    path_end = path_start + duration
    max_rows = math.floor(cap / dt + 1e-9) + 1
    tr = Trace.allocate(max_rows, leader.n, follower.n)
    q_l = leader.check_q(initial.q_l, "initial q_l").copy()
    q_f = follower.check_q(initial.q_f, "initial q_f").copy()
    sigma = float(initial.sigma)
    sigma_l = float(initial.sigma_leader)
    tau = path_start
    t_wall = path_start
    pre: tuple[float, float] | None = None  # closure error before correction, if any
    corr = (0.0, 0.0)
    controller.reset(initial_rates)
    v_start = controller.applied
    refused = (_before_the_run(controller, DualArmState(path_start, q_l, q_f, sigma, sigma_l),
                               path_end) if preflight else None)
    if refused is not None:
        return RolloutResult(tr.truncate(0), refused[0], controller.solver.name, dt,
                             path_start, path_end,
                             _realised(controller, tr.truncate(0), dt, v_start), hard,
                             extras=refused[1])
    if plant is not None:  # after the preflight: a run it refuses does not pay the settle
        plant.reset(DualArmState(path_start, q_l, q_f, sigma, sigma_l), dt)
    failure: Failure | None = None
    warnings: list[str] = []
    projection_failures = 0
    window = (t_wall, tau)  # start of the current stall-detection window
    end_tol = 1e-9 * max(1.0, abs(path_end))
    rows = 0  # samples recorded whole
    interrupted: KeyboardInterrupt | None = None
    planned: dict[str, tuple[float, float]] | None = None  # the plan's own errors (plant)
    plant_lag = False  # the failure is the plant's: it did not follow the command
    try:
        for k in range(max_rows):
            state = DualArmState(tau, q_l, q_f, sigma, sigma_l)
            at_end = tau >= path_end - end_tol
            scale_max = 0.0 if at_end else min(1.0, (path_end - tau) / dt)
            try:
                out = controller.step(state, scale_max=scale_max)
            except DualArmError as err:
                # The state was reached: keep it (with no command) before stopping.
                record_state(tr, k, t_wall, state, controller,
                             "infeasible" if isinstance(err, InfeasibleStepError) else "error")
                rows = k + 1
                message = f"step {k} at t = {t_wall:.4f} s: {err}"
                if at_end:  # the path is done; this command would not be applied
                    warnings.append(f"the command at the path's end failed: {message}")
                else:
                    failure = Failure("support" if isinstance(err, SupportLostError)
                                      else "solver", k, t_wall, math.nan, math.nan, message)
                    if isinstance(err, InfeasibleStepError):  # policy "stop": say why
                        failure = plainly(controller, state, failure, None, err.conflicts)
                break
            record(tr, k, t_wall, state, out, controller)
            if at_end and k:  # not applied: keep the task scale the path ended at
                tr.scale[k] = tr.scale[k - 1]
            tr.closure_pos_err_pre[k], tr.closure_rot_err_pre[k] = (
                pre if pre is not None else (tr.closure_pos_err[k], tr.closure_rot_err[k]))
            tr.correction_l[k], tr.correction_f[k] = corr
            rows = k + 1
            # The command at the path's end is not applied: it cannot fail the run.
            failure = _sample_failure(tr, k, out.applied or at_end, out.status.value,
                                      out.solution.message, limits, warnings,
                                      speed_limited=controller.options.velocity_limits)
            if failure is not None and planned is not None and failure.criterion in (
                    "closure", "tracking"):  # measured: was it the plan's own error?
                lagged = not_followed(failure, planned, limits.closure
                                      if failure.criterion == "closure" else limits.tracking)
                failure = failure if lagged is None else lagged
                plant_lag = lagged is not None
            if failure is not None and failure.criterion == "solver":  # say why, plainly
                failure = plainly(controller, state, failure, out.build.problem,
                                  out.solution.extras.get("conflicts", ()))
            if failure is None and t_wall - window[0] >= limits.stall_time - 1e-9:
                if tau - window[1] < 0.01 * (t_wall - window[0]):
                    failure = Failure(
                        "stalled", k, t_wall, tau - window[1], 0.01 * (t_wall - window[0]),
                        f"step {k} at t = {t_wall:.4f} s: path stalled: the object advanced "
                        f"{tau - window[1]:.3g} s along its path in "
                        f"{t_wall - window[0]:.3g} s (task scale {tr.scale[k]:.3g}; "
                        f"smallest singular values: leader "
                        f"{tr.sigma_min_l[k]:.3g}, follower {tr.sigma_min_f[k]:.3g}); last "
                        f"solver message: {out.solution.message}")
                window = (t_wall, tau)
            if failure is not None:
                break
            if progress is not None:
                progress(min((tau - path_start) / duration, 1.0),
                         _time_lost(t_wall - path_start, tau - path_start, dt))
            if at_end or k == max_rows - 1:
                break
            if plant is None:
                nxt = state.advanced(out, dt)
            else:
                nxt = plant.advance(state, out, dt)
                planned = planned_errors(task, state, out, dt)
            tau, q_l, q_f, sigma, sigma_l = (nxt.t, nxt.q_l, nxt.q_f, nxt.sigma,
                                             nxt.sigma_leader)
            t_wall = t_wall + dt
            pre, corr = None, (0.0, 0.0)
            if reresolve_orientation or project:
                pre = task.closure_error(q_l, q_f, sigma, sigma_l)
                q_l0, q_f0 = q_l, q_f
                if reresolve_orientation:
                    q_f = _reresolve(controller, q_l, q_f, sigma, sigma_l)
                if project:
                    q_l, ok_l = _project(leader, task.leader_target(tau, sigma_l), q_l)
                    q_f, ok_f = _project(follower, task.follower_target(q_l, sigma, sigma_l),
                                         q_f)
                    projection_failures += (not ok_l) + (not ok_f)
                corr = (float(np.abs(q_l - q_l0).max(initial=0.0)),
                        float(np.abs(q_f - q_f0).max(initial=0.0)))
    except KeyboardInterrupt as exc:
        if not stop_on_interrupt:
            raise
        interrupted = exc
    trace = tr.truncate(rows)
    record_margins(trace, task)
    realised = _realised(controller, trace, dt, v_start)
    if interrupted is not None:
        t_last = float(trace.t[-1]) if rows else path_start
        failure = Failure("interrupted", max(rows - 1, 0), t_last, math.nan, math.nan,
                          f"interrupted ({str(interrupted) or 'KeyboardInterrupt'}) after "
                          f"{rows} samples, at t = {t_last:.4f} s")
    if failure is None and len(trace) and trace.tau[-1] < path_end - end_tol:
        done = (trace.tau[-1] - path_start) / duration
        failure = Failure(
            "path_incomplete", len(trace) - 1, float(trace.t[-1]), done, 1.0,
            f"path not completed: {100 * done:.1f}% of the path in {cap:g} s "
            f"(the duration cap; the task was slowed)")
    if failure is None and hard:
        failure = _realised_failure(realised, trace, dt)
        if failure is not None and plant is not None:  # measured, not commanded: tell
            warnings.append(f"the measured motion left a limit: {failure.message}")
            failure = None
    clearance = record_clearance(task, trace)
    loads = record_loads(task, trace)  # the wrench each hand applies (a task with a load)
    torque = record_torques(controller, trace)  # each joint's torque (a load or limits)
    if loads is not None and loads.warning():
        warnings.append(str(loads.warning()))
    if task.scene is not None:
        overlapping = task.scene.overlapping_at_start()
        if overlapping:
            warnings.append("collision pairs left out because their shapes overlap at the "
                            f"start (not checked during the run): {', '.join(overlapping)}; "
                            "move the arms apart or add the pairs to collision.exclude")
    if clearance is not None:
        if failure is None and clearance.enforced and not clearance.kept:
            failure = clearance_failure(clearance, trace)
        elif clearance.minimum < 0.0 and not clearance.enforced:
            warnings.append(f"the recorded motion penetrates: {clearance.pair} at "
                            f"{clearance.minimum * 1e3:.1f} mm (sample {clearance.sample}; "
                            "collision avoidance is off)")
    if torque is not None and failure is None and torque.enforced and not torque.kept:
        if plant is None:
            failure = torque_failure(torque, trace)
        else:  # quasi-static torques at measured states, not commanded ones: tell
            warnings.append("the measured motion left a limit: "
                            f"{torque_failure(torque, trace).message}")
    if failure is not None and failure.criterion in (*EXPLAINED, "solver") and len(trace):
        failure = blocked_by_pair(controller, trace, failure)
    if (failure is not None and plant is None
            and failure.criterion in (*EXPLAINED, "solver") and len(trace)):
        # With a plant, a failure at a measured state may be the plant's own (a diverged
        # simulation): it is not relabelled.
        failure = blocked_by_torque(controller, trace, failure)
    if failure is not None and failure.criterion in EXPLAINED and len(trace) and not plant_lag:
        failure = _explained(controller, trace, failure)
    return RolloutResult(
        trace, failure, controller.solver.name, dt, path_start, path_end, realised, hard,
        warnings=warnings, clearance=clearance, torque=torque,
        extras={**({} if task.scene is None else {"collision": task.scene.summary()}),
                **({} if loads is None else {"loads": loads.as_dict()}),
                "projection": project, "reresolve_orientation": reresolve_orientation,
                "projection_failures": projection_failures,
                "closure_tolerance_m_rad": list(limits.closure),
                "tracking_tolerance_m_rad": list(limits.tracking),
                "singular_value_min": limits.singular_value_min,
                "duration_cap_s": cap})


def _before_the_run(controller: DualArmController, start: DualArmState, path_end: float
                    ) -> tuple[Failure, dict[str, Any]] | None:
    """Return the failure of a run refused before its first sample, and its record.

    In order: a waypoint out of reach (``"unreachable"``), a joint beyond its torque
    limit at the start (``"torque"``), a collision pair closer than the safety distance
    less the allowance at the start (``"collision"``), a path through an obstacle
    (``"path_collision"``). None when the run may start.
    """
    task, dt, t0 = controller.task, controller.options.dt, float(start.t)
    miss = unreachable_waypoint(task, start, path_end, within_ranges=controller.hard_bounds)
    if miss is not None:
        return (Failure("unreachable", 0, t0, miss.position_error, REACH_TOLERANCE[0],
                        f"before the run: {miss.message}"),
                {"unreachable": {"arm": miss.arm, "waypoint": miss.waypoint, "t_s": miss.t}})
    heavy = torque_at_start(controller, start)
    if heavy is not None:
        return (Failure("torque", 0, t0, heavy.torque, heavy.limit,
                        f"before the run: {heavy.message}"),
                {"torque_at_start": {"joint": heavy.joint, "torque_N_m": heavy.torque,
                                     "limit_N_m": heavy.limit}})
    close = clearance_at_start(task, start)
    if close is not None:
        return (Failure("collision", 0, t0, close.distance, close.limit,
                        f"before the run: {close.message}"),
                {"collision_at_start": {"pair": close.pair, "distance_m": close.distance,
                                        "safety_distance_m": close.safety_distance}})
    blocked = path_collision_of(task, t0, path_end, dt)
    if blocked is not None:
        return (Failure("path_collision", 0, blocked.t, blocked.distance,
                        blocked.safety_distance, f"before the run: {blocked.message}"),
                {"path_collision": {"obstacle": blocked.obstacle, "t_s": blocked.t,
                                    "distance_m": blocked.distance}})
    return None


def _time_lost(elapsed: float, advanced: float, dt: float) -> float:
    """Time lost to slowing [s] when the path time advanced by ``advanced`` [s] in ``elapsed``.

    The elapsed time minus the whole samples of ``dt`` [s] the advance takes at full
    speed: the shortened last sample where the path ends is no loss. Rounded to the
    nanosecond, so that a run that lost no time says 0, not rounding noise.
    """
    return max(round(elapsed - dt * math.ceil(advanced / dt - 1e-9), 9), 0.0)


def _sample_failure(tr: Trace, k: int, applied: bool, status: str, message: str,
                    limits: RunLimits, warnings: list[str], *, speed_limited: bool
                    ) -> Failure | None:
    """Return the first criterion sample ``k`` breaks, or None (appends warnings)."""
    t = float(tr.t[k])
    checks = (
        ("closure", "grasp closure lost", tr.closure_pos_err[k], tr.closure_rot_err[k],
         limits.closure),
        ("tracking", "leader left its path", tr.leader_pos_err[k], tr.leader_rot_err[k],
         limits.tracking),
    )
    for criterion, what, pos, rot, (tol_pos, tol_rot) in checks:
        if pos > tol_pos or rot > tol_rot:
            ratio_pos, ratio_rot = pos / tol_pos, rot / tol_rot
            amount, limit = (pos, tol_pos) if ratio_pos >= ratio_rot else (rot, tol_rot)
            hint = ""
            if criterion == "closure" and not speed_limited:
                hint = ("; controller.velocity_limits is off, so one step may move the grasp "
                        "and the joints this far, beyond where the linearised closure "
                        "(Eq. 25) holds: turn the speed limits on")
            return Failure(criterion, k, t, float(amount), limit,
                           f"{_at(k, t)}: {what}: {pos:.3g} m, {rot:.3g} rad "
                           f"(tolerance {tol_pos:g} m, {tol_rot:g} rad){hint}")
    threshold = limits.singular_value_min
    if threshold > 0 and limits.singularity_action != "ignore":
        for arm, sv in (("leader", tr.sigma_min_l[k]), ("follower", tr.sigma_min_f[k])):
            if sv < threshold:
                text = (f"{_at(k, t)}: the {arm} is near a singularity (smallest singular value "
                        f"of its Jacobian {sv:.3g}, threshold {threshold:g})")
                if limits.singularity_action == "stop":
                    return Failure("singularity", k, t, float(sv), threshold, text)
                if not any(f"the {arm} is near a singularity" in w for w in warnings):
                    warnings.append(f"first at {text}")
    if not applied:
        return Failure("solver", k, t, math.nan, math.nan,
                       f"{_at(k, t)}: solver status {status}: {message}")
    return None


def _at(k: int, t: float) -> str:
    """Where a sample's message happens: ``"step 12 at t = 0.1200 s"`` (made only when needed)."""
    return f"step {k} at t = {t:.4f} s"


def _explained(controller: DualArmController, trace: Trace, failure: Failure) -> Failure:
    """``failure`` with its cause appended (:func:`.diagnosis.explain` at its sample)."""
    k = min(failure.sample, len(trace) - 1)
    state = trace.state(k)
    try:
        why = controller.explain(state)
    except DualArmError:  # the state itself cannot be posed: say nothing more
        return failure
    return dataclasses.replace(failure, message=f"{failure.message}; {why}")


def _realised(controller: DualArmController, trace: Trace, dt: float,
              v_start: FloatArray | None = None) -> dict[str, LimitReport]:
    """Measure the realised motion of both arms and of the grasp against their limits.

    ``v_start`` holds the rates the run started with (decision order; default zero).
    Speeds and accelerations are measured against the arms' limits always; they decide
    completion only when the step imposed them (``velocity_limits``,
    ``acceleration_limits``).
    """
    task, opts = controller.task, controller.options
    lay = controller.layout
    start = lay.split(np.zeros(lay.n) if v_start is None else v_start)
    reports = {}
    speed_rule = opts.velocity_limits
    accel_rule = opts.acceleration_limits
    for role, arm, q, v0 in (("leader", task.leader, trace.q_l, start[0]),
                             ("follower", task.follower, trace.q_f, start[1])):
        prefix = "ql" if role == "leader" else "qf"
        reports[role] = measure(q, arm.q_min, arm.q_max, arm.qd_max, dt,
                                [f"{prefix}{j + 1}" for j in range(arm.n)],
                                speed_rule=speed_rule, a_max=arm.qdd_max, v_start=v0,
                                acceleration_rule=accel_rule, j_max=arm.qddd_max,
                                jerk_rule=opts.jerk_limits)
    surface = task.surface
    a_grasp = np.array([opts.grasp_acc_max])
    reports["grasp"] = measure(trace.grasp[:, None], np.array([surface.sigma_min]),
                               np.array([surface.sigma_max]),
                               np.array([opts.grasp_speed_max]), dt, ["grasp"],
                               speed_rule=speed_rule, a_max=a_grasp,
                               v_start=np.array([start[2]]), acceleration_rule=accel_rule,
                               j_max=np.array([opts.grasp_jerk_max]), jerk_rule=opts.jerk_limits)
    lead = task.leader_surface
    if lead is not None:
        reports["grasp_leader"] = measure(
            trace.grasp_leader[:, None], np.array([lead.sigma_min]), np.array([lead.sigma_max]),
            np.array([opts.grasp_speed_max]), dt, ["grasp_leader"], speed_rule=speed_rule,
            a_max=a_grasp, v_start=np.array([start[3]]), acceleration_rule=accel_rule)
    return reports


def clearance_failure(report: ClearanceReport, trace: Trace) -> Failure:
    """Return the failure of a run whose recorded clearance fell below ``d_s - allowance``."""
    k = report.breach_sample
    t = float(trace.t[k])
    d = float(min(trace.clearance_arm_arm[k], trace.clearance_arm_object[k],
                  trace.clearance_obstacles[k], trace.clearance_self[k]))
    limit = report.safety_distance - report.allowance
    return Failure("collision", k, t, d, limit,
                   f"step {k} at t = {t:.4f} s: the recorded motion brought "
                   f"{trace.clearance_pair[k]} to {d * 1e3:.2f} mm, below the safety "
                   f"distance {report.safety_distance * 1e3:.1f} mm less the allowance "
                   f"{report.allowance * 1e3:.1f} mm")


def torque_failure(report: TorqueReport, trace: Trace) -> Failure:
    """Return the failure of a run whose recorded torque went beyond its limit and allowance.

    A run whose grasps could not hold the load at some sample (no torque there) fails at
    the first such sample.
    """
    if report.breach_sample < 0 or 0 <= report.first_unbalanced < report.breach_sample:
        k = report.first_unbalanced
        t = float(trace.t[k])
        return Failure("torque", k, t, math.nan, math.nan,
                       f"step {k} at t = {t:.4f} s: the grasps cannot hold the load there, "
                       f"so the joint torques are not known ({report.unbalanced} such "
                       "samples)")
    k = report.breach_sample
    t = float(trace.t[k])
    tau = np.r_[trace.tau_leader[k], trace.tau_follower[k]]
    n_l = trace.tau_leader.shape[1]
    names = [f"ql{i + 1}" for i in range(n_l)] + [f"qf{i + 1}"
                                                   for i in range(trace.tau_follower.shape[1])]
    j = names.index(report.breach_joint)
    limit = report.breach_limit
    return Failure("torque", k, t, float(tau[j]), limit,
                   f"step {k} at t = {t:.4f} s: the recorded motion needs "
                   f"{tau[j]:.4g} N m at joint {report.breach_joint}, beyond its limit of "
                   f"{limit:.4g} N m and the allowance of {100 * report.allowance_rtol:g}%")


def _realised_failure(realised: dict[str, LimitReport], trace: Trace, dt: float
                      ) -> Failure | None:
    """Return the earliest realised-limit breach of a hard-limit run, as a failure."""
    breaches = [r.breach for r in realised.values() if r.breach is not None]
    if not breaches:
        return None
    b = min(breaches, key=lambda b: b.sample)
    t = float(trace.t[b.sample])
    return Failure(b.criterion, b.sample, t, b.amount, b.limit,
                   f"step {b.sample} at t = {t:.4f} s: realised motion broke a limit: "
                   f"{b.describe(dt)}")


def _project(arm: SerialArm, T_target: FloatArray, q: FloatArray) -> tuple[FloatArray, bool]:
    """Move ``q`` onto ``T_target`` by damped Gauss-Newton from the integrated guess.

    Only for the paper's methods, which ignore limits (see :func:`rollout`). Returns the
    corrected joints (never worse than ``q``: only steps that lower the error are taken)
    and whether the correction converged to 1e-9 m and rad.
    """
    res = ik_dls(arm, T_target, q, tol_pos=1e-12, tol_rot=1e-12, max_iter=5,
                 respect_limits=False, raise_on_failure=False)
    return res.q, res.position_error <= 1e-9 and res.rotation_error <= 1e-9


def _reresolve(controller: DualArmController, q_l: FloatArray, q_f: FloatArray,
               sigma: float, sigma_l: float) -> FloatArray:
    """Sec. 3.3: turn the follower's hand to the grasp frame at the new ``sigma``."""
    task = controller.task
    T_target = task.follower_target(q_l, sigma, sigma_l)
    T_f, J = task.follower.fk_jacobian(q_f)
    dw = pin.log3(T_target[:3, :3] @ T_f[:3, :3].T)
    twist = np.concatenate((np.zeros(3), dw))
    dq = factor(J).solve(twist)  # rank decided at RANK_RTOL, as every step's
    return q_f + dq


__all__ = ["CRITERIA", "SINGULARITY_ACTIONS", "Failure", "RolloutResult", "RunLimits",
           "rollout"]
