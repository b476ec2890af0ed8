"""The rollout: integrate the controller along the path and record every sample."""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import DualArmError, InvalidInputError
from ..kinematics.arm import SerialArm
from ..kinematics.ik import ik_dls
from ..se3 import rotation_error
from ..step.build import DualArmState
from .controller import ControlOutput, DualArmController

FloatArray = NDArray[np.float64]


@dataclass
class Trace:
    """Everything recorded along a rollout, one row per sample.

    Row k holds the state at time ``t[k]`` and the command computed from it; the
    command of the last row is computed but not integrated.
    """

    t: FloatArray
    tau: FloatArray
    q_l: FloatArray
    q_f: FloatArray
    grasp: FloatArray
    m: FloatArray
    ql_dot: FloatArray
    qf_dot: FloatArray
    closure_pos_err: FloatArray
    closure_rot_err: FloatArray
    leader_pos_err: FloatArray
    leader_rot_err: FloatArray
    margin_qf: FloatArray
    margin_ql: FloatArray
    margin_grasp: FloatArray
    scale: FloatArray
    status: list[str]
    objective: FloatArray
    eq_residual: FloatArray
    bound_violation: FloatArray
    kinematics_time_s: FloatArray
    assembly_time_s: FloatArray
    solve_time_s: FloatArray
    step_time_s: FloatArray

    @classmethod
    def allocate(cls, rows: int, n_l: int, n_f: int) -> Trace:
        """Arrays for ``rows`` samples, filled with NaN until written."""
        def v(*shape: int) -> FloatArray:
            return np.full((rows, *shape), np.nan)

        return cls(
            t=v(), tau=v(), q_l=v(n_l), q_f=v(n_f), grasp=v(), m=v(), ql_dot=v(n_l),
            qf_dot=v(n_f), closure_pos_err=v(), closure_rot_err=v(), leader_pos_err=v(),
            leader_rot_err=v(), margin_qf=v(n_f), margin_ql=v(n_l), margin_grasp=v(),
            scale=v(), status=[""] * rows, objective=v(), eq_residual=v(),
            bound_violation=v(), kinematics_time_s=v(), assembly_time_s=v(),
            solve_time_s=v(), step_time_s=v(),
        )

    def truncate(self, rows: int) -> Trace:
        """Return the first ``rows`` samples."""
        kw: dict[str, Any] = {}
        for name in self.__dataclass_fields__:
            val = getattr(self, name)
            kw[name] = val[:rows]
        return Trace(**kw)

    def __len__(self) -> int:
        return int(self.t.shape[0])


@dataclass
class RolloutResult:
    """Outcome of a rollout.

    Attributes
    ----------
    trace : Trace
        The samples that were completed.
    completed : bool
        True when the whole duration was run.
    message : str
        Why the run stopped early ("" when completed).
    solver : str
        Solver name.
    dt : float
        Sampling interval [s].
    """

    trace: Trace
    completed: bool
    message: str
    solver: str
    dt: float
    extras: dict[str, Any] = field(default_factory=dict)

    def summary(self, arm_limits: dict[str, Any] | None = None) -> dict[str, Any]:
        """Scalars that sum the run up (JSON-ready)."""
        tr = self.trace
        n = len(tr)
        counts = Counter(tr.status)
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
            "samples": n,
            "dt_s": self.dt,
            "t_end_s": float(tr.t[-1]) if n else 0.0,
            "path_time_end_s": float(tr.tau[-1]) if n else 0.0,
            "status_counts": dict(sorted(counts.items())),
            "time_lost_to_scaling_s": float(np.nansum(1.0 - tr.scale[:-1]) * self.dt)
            if n > 1 else 0.0,
            "closure_pos_err_max_m": fmax(tr.closure_pos_err),
            "closure_rot_err_max_rad": fmax(tr.closure_rot_err),
            "leader_pos_err_max_m": fmax(tr.leader_pos_err),
            "leader_rot_err_max_rad": fmax(tr.leader_rot_err),
            "grasp_start_m": float(tr.grasp[0]) if n else float("nan"),
            "grasp_end_m": float(tr.grasp[-1]) if n else float("nan"),
            "grasp_min_m": fmin(tr.grasp),
            "grasp_max_m": fmax(tr.grasp),
            "margin_qf_min_rad": fmin(tr.margin_qf),
            "margin_qf_start_rad": fmin(tr.margin_qf[:1]),
            "margin_qf_min_after_start_rad": fmin(tr.margin_qf[1:]),
            "margin_qf_min_per_joint_rad": [fmin(tr.margin_qf[:, j])
                                            for j in range(tr.margin_qf.shape[1])],
            "margin_ql_min_rad": fmin(tr.margin_ql),
            "margin_grasp_min_m": fmin(tr.margin_grasp),
            "end_inside_all_ranges": bool(
                n and np.nanmin(tr.margin_qf[-1]) >= -1e-9 and tr.margin_grasp[-1] >= -1e-9
            ),
            "bound_violation_max": fmax(tr.bound_violation),
            "eq_residual_max": fmax(tr.eq_residual),
            "solve_time_median_s": float(np.median(solve)) if solve.size else float("nan"),
            "solve_time_p99_s": float(np.percentile(solve, 99)) if solve.size else float("nan"),
            "step_time_median_s": float(np.median(step)) if step.size else float("nan"),
            "step_time_p99_s": float(np.percentile(step, 99)) if step.size else float("nan"),
        }
        out.update(self.extras)
        return out


def _margins(q: FloatArray, lo: FloatArray, hi: FloatArray) -> FloatArray:
    """Signed distance to the nearest limit per joint (negative outside) [rad]."""
    return np.minimum(q - lo, hi - q)


def rollout(
    controller: DualArmController,
    initial: DualArmState,
    *,
    duration: float,
    reresolve_orientation: bool | None = None,
    project: bool = True,
    closure_tolerance: tuple[float, float] = (1e-3, 1e-2),
    stall_time: float = 1.0,
    progress: Callable[[int, int], None] | None = None,
) -> RolloutResult:
    """Run ``controller`` from ``initial`` for ``duration`` seconds of simulated time.

    Each sample: the controller computes the command from the current state; the
    leader integrates ``ql_dot * dt``, the follower ``qf_dot * dt`` and the grasp
    ``m * dt``; the path time advances by ``scale * dt`` (a scaled step slows the
    object). On a curved path with the paper's frozen-orientation Jacobian, the
    follower's orientation is re-resolved after each step (Sec. 3.3).

    Euler integration leaves an error of second order in ``dt`` per step. The
    controller's closure feedback (``correction_gain``) removes it over the following
    steps, as it would on a real arm; with ``project=True`` the rollout also corrects
    the drift at once, at position level: a few Gauss-Newton iterations move the
    leader onto ``D(path time) H1^-1`` and the follower onto the grasp closure (the
    grasp coordinate is kept). Both are recorded in the trace as errors before the
    next step.

    Parameters
    ----------
    controller : DualArmController
        The per-step controller.
    initial : DualArmState
        State at ``t = initial.t``.
    duration : float
        Length of the run [s].
    reresolve_orientation : bool, optional
        Apply the Sec. 3.3 re-resolution; default: when the path is curved and the
        controller does not use the exact orientation Jacobian.
    project : bool
        Correct the integration drift of both arms after every step (see above).
        Corrections that do not converge are counted in the summary
        (``projection_failures``).
    closure_tolerance : tuple of float
        ``(position [m], rotation [rad])``: a sample whose grasp closure error exceeds
        either stops the run as failed ("grasp closure lost"): the object would be
        torn or dropped. Default (1 mm, 0.01 rad).
    stall_time : float
        A run whose path time advances by less than 1% of the time elapsed over a
        window of this length [s] (the task scaled to nearly 0: it cannot move) stops
        as failed ("path stalled").
    progress : callable, optional
        Called as ``progress(done, total)`` after every sample.

    Returns
    -------
    RolloutResult
        Never raises for a failed step: the run stops, and the result says why
        (``completed=False``) while keeping every completed sample.
    """
    if not (math.isfinite(duration) and duration > 0):
        raise InvalidInputError(f"duration must be a positive number of seconds, got {duration}")
    task = controller.task
    leader, follower, surface = task.leader, task.follower, task.surface
    dt = controller.options.dt
    steps = math.floor(duration / dt + 1e-9)
    rows = steps + 1
    tr = Trace.allocate(rows, leader.n, follower.n)
    q_l = leader.check_q(initial.q_l, "initial q_l").copy()
    q_f = follower.check_q(initial.q_f, "initial q_f").copy()
    sigma = float(initial.sigma)
    tau = float(initial.t)
    t_wall = float(initial.t)
    if reresolve_orientation is None:
        curved = float(np.linalg.norm(surface.angular_rate(sigma))) > 0.0 or bool(
            getattr(surface, "curved", False)
        )
        reresolve_orientation = curved and not controller.options.exact_orientation
    tol_pos, tol_rot = closure_tolerance
    if not (tol_pos > 0 and tol_rot > 0):
        raise InvalidInputError(f"closure_tolerance must be positive, got {closure_tolerance}")
    controller.reset()
    completed, message = True, ""
    projection_failures = 0
    window = (t_wall, tau)  # start of the current stall-detection window
    k = 0
    for k in range(rows):
        state = DualArmState(tau, q_l, q_f, sigma)
        try:
            out = controller.step(state)
        except DualArmError as err:
            completed, message = False, f"step {k} at t = {t_wall:.4f} s: {err}"
            break
        _record(tr, k, t_wall, state, out, controller)
        if tr.closure_pos_err[k] > tol_pos or tr.closure_rot_err[k] > tol_rot:
            completed = False
            message = (f"step {k} at t = {t_wall:.4f} s: grasp closure lost: "
                       f"{tr.closure_pos_err[k]:.3g} m, {tr.closure_rot_err[k]:.3g} rad "
                       f"(tolerance {tol_pos:g} m, {tol_rot:g} rad)")
            k += 1
            break
        if t_wall - window[0] >= stall_time - 1e-9:
            if tau - window[1] < 0.01 * (t_wall - window[0]):
                completed = False
                message = (f"step {k} at t = {t_wall:.4f} s: path stalled: the object "
                           f"advanced {tau - window[1]:.3g} s along its path in "
                           f"{t_wall - window[0]:.3g} s (task scaled to nearly 0); last "
                           f"solver message: {out.solution.message}")
                k += 1
                break
            window = (t_wall, tau)
        if not out.applied:
            completed = False
            message = (f"step {k} at t = {t_wall:.4f} s: solver status "
                       f"{out.status.value}: {out.solution.message}")
            k += 1
            break
        if progress is not None:
            progress(k + 1, rows)
        if k == rows - 1:
            k += 1
            break
        q_l = q_l + dt * out.ql_dot
        q_f = q_f + dt * out.qf_dot
        sigma = sigma + dt * out.m
        tau = tau + dt * out.scale
        t_wall = t_wall + dt
        if reresolve_orientation:
            q_f = _reresolve(controller, q_l, q_f, sigma)
        if project:
            q_l, ok_l = _project(leader, task.leader_target(tau), q_l)
            q_f, ok_f = _project(follower, task.follower_target(q_l, sigma), q_f)
            projection_failures += (not ok_l) + (not ok_f)
    trace = tr if k >= rows else tr.truncate(k)
    return RolloutResult(trace, completed and k >= rows, message, controller.solver.name, dt,
                         extras={"projection": project,
                                 "projection_failures": projection_failures,
                                 "closure_tolerance_m_rad": list(closure_tolerance)})


def _project(arm: SerialArm, T_target: FloatArray, q: FloatArray) -> tuple[FloatArray, bool]:
    """Move ``q`` onto ``T_target`` by damped Gauss-Newton from the integrated guess.

    Joint limits are not imposed here: the step's bounds already kept the joints in
    range, and the correction is of the order of the integration error (``dt^2``).
    Returns the corrected joints (never worse than ``q``: only steps that lower the
    error are taken) and whether the correction converged to 1e-9 m and rad.
    """
    res = ik_dls(arm, T_target, q, tol_pos=1e-12, tol_rot=1e-12, max_iter=5,
                 respect_limits=False, raise_on_failure=False)
    return res.q, res.position_error <= 1e-9 and res.rotation_error <= 1e-9


def _reresolve(controller: DualArmController, q_l: FloatArray, q_f: FloatArray,
               sigma: float) -> FloatArray:
    """Sec. 3.3: turn the follower's hand to the grasp frame at the new ``sigma``."""
    task = controller.task
    T_target = task.follower_target(q_l, sigma)
    T_f, J = task.follower.fk_jacobian(q_f)
    dw = rotation_error(T_target[:3, :3], T_f[:3, :3])
    twist = np.concatenate((np.zeros(3), dw))
    try:
        dq = np.linalg.lstsq(J, twist, rcond=None)[0]
    except np.linalg.LinAlgError:
        return q_f
    return q_f + dq


def _record(tr: Trace, k: int, t: float, state: DualArmState, out: ControlOutput,
            controller: DualArmController) -> None:
    task = controller.task
    leader, follower, surface = task.leader, task.follower, task.surface
    tr.t[k] = t
    tr.tau[k] = state.t
    tr.q_l[k] = state.q_l
    tr.q_f[k] = state.q_f
    tr.grasp[k] = state.sigma
    tr.m[k] = out.m
    tr.ql_dot[k] = out.ql_dot
    tr.qf_dot[k] = out.qf_dot
    err = out.build.closure_error
    tr.closure_pos_err[k] = float(np.linalg.norm(err[:3]))
    tr.closure_rot_err[k] = float(np.linalg.norm(err[3:]))
    le = out.leader_error
    tr.leader_pos_err[k] = float(np.linalg.norm(le[:3]))
    tr.leader_rot_err[k] = float(np.linalg.norm(le[3:]))
    tr.margin_qf[k] = _margins(state.q_f, follower.q_min, follower.q_max)
    tr.margin_ql[k] = _margins(state.q_l, leader.q_min, leader.q_max)
    tr.margin_grasp[k] = _grasp_margin(surface, state.sigma)
    tr.scale[k] = out.scale
    tr.status[k] = out.status.value
    sol = out.solution
    tr.objective[k] = sol.objective
    tr.eq_residual[k] = sol.eq_residual
    tr.bound_violation[k] = sol.bound_violation
    tr.kinematics_time_s[k] = out.times.kinematics
    tr.assembly_time_s[k] = out.times.assembly
    tr.solve_time_s[k] = out.times.solve
    tr.step_time_s[k] = out.times.total


def _grasp_margin(surface: Any, sigma: float) -> float:
    """Signed distance of the grasp to the nearest end of its range [m]."""
    lo = surface.sigma_min
    hi = surface.sigma_max
    r = surface.point(sigma)
    s = surface.tangent(sigma)
    margin = min(sigma - lo, hi - sigma)
    for i in range(3):
        if abs(s[i]) < 1e-12:
            continue
        for bound, sign in ((surface.r_min[i], 1.0), (surface.r_max[i], -1.0)):
            if math.isfinite(bound):
                margin = min(margin, sign * (r[i] - bound) / abs(s[i]))
    return float(margin)


__all__ = ["RolloutResult", "Trace", "rollout"]
