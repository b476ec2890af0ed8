"""The joint torques of a run: before it, along it (recorded), and what they decide.

* before the first sample, :func:`torque_at_start` asks whether the arms can hold the
  load at the start at all: a joint beyond its limit there fails the run on criterion
  ``"torque"`` before it moves (its rows could only ask the torque back in one sample);
* a run that stalled, ran out of time or found no step is re-read by
  :func:`blocked_by_torque`: when a torque row is what stops the task at the failing
  state (the load is beyond the arms there), the failure becomes criterion
  ``"torque"``, naming the joint and its torque;
* after the last, :func:`record_torques` computes every recorded sample's quasi-static
  joint torques (:mod:`dualarm_qp.task.torques`: each hand's wrench moved from its grasp
  point to the tool point whose Jacobian carries it, as the step's torque rows do) into
  the trace's ``tau_leader`` and ``tau_follower`` and reports the largest use of each
  limit. With torque limits on, a
  run completes only if every recorded torque stays within ``tau_max + allowance``.

The **allowance** is :data:`TORQUE_RTOL` of each joint's limit. The step keeps the
torques of the next sample to first order; the rest is second order in the step,
``dt^2 x^T (d^2 tau / dy^2) x / 2``: at 0.01 s and 1 rad/s with curvatures of tens of
N m/rad^2 that is a few mN m, well within 0.1% of a limit of tens of N m.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ..errors import DualArmError
from ..solvers._scale import max_task_scale
from ..step.limits.torque import ROW_PREFIX
from ..step.state import DualArmState
from ..task.hands import hand_statics
from ..task.torques import LoadTorques, model_effort, torque_limits_of
from .trace import Trace

if TYPE_CHECKING:
    from .controller import DualArmController
    from .failure import Failure

FloatArray = NDArray[np.float64]

#: Allowance on a recorded torque, relative to the joint's limit (see the module docstring).
TORQUE_RTOL = 1e-3

#: A task scale below this at the failing state counts as stopped by its blocking rows
#: (as for collision rows).
BLOCKED_SCALE = 0.01

__all__ = ["BLOCKED_SCALE", "TORQUE_RTOL", "TorqueReport", "blocked_by_torque",
           "joint_torque_limits", "record_torques", "torque_at_start"]


def joint_torque_limits(controller: DualArmController) -> FloatArray:
    """Both arms' joint torque limits [N m], the leader's first (``inf`` where none is known).

    The configured ``tau_max`` or the arm's ``effort``; with torque limits off a joint
    without either is reported against no limit.
    """
    task, opts = controller.task, controller.options
    out = []
    for arm, given, role in ((task.leader, opts.leader_tau_max, "leader"),
                             (task.follower, opts.follower_tau_max, "follower")):
        if opts.torque_limits:
            out.append(torque_limits_of(arm, given, role))
        else:
            out.append(model_effort(arm) if given is None
                       else np.asarray(given, dtype=np.float64))
    return np.concatenate(out)


@dataclass(frozen=True)
class TorqueReport:
    """The recorded run's joint torques against their limits (``realised_limits.torque``).

    Attributes
    ----------
    ratio : float
        ``max |tau| / tau_max`` over samples and limited joints (NaN: no limit known).
    joint : str
        The joint that reached it (``"qf2"``).
    sample : int
        Where.
    peak : float
        Its torque there [N m].
    limit : float
        Its limit [N m].
    allowance_rtol : float
        :data:`TORQUE_RTOL`.
    enforced : bool
        Whether the step kept torque limits.
    breach_sample : int
        The first sample with a torque beyond ``tau_max (1 + allowance)`` (-1: none).
    breach_joint : str
        Its joint ("" for none).
    unbalanced : int
        Samples where the grasps could not hold the load (torques NaN).
    breach_limit : float
        The breaching joint's limit [N m] (NaN: none).
    first_unbalanced : int
        The first of the ``unbalanced`` samples (-1: none).
    """

    ratio: float
    joint: str
    sample: int
    peak: float
    limit: float
    allowance_rtol: float
    enforced: bool
    breach_sample: int
    breach_joint: str
    unbalanced: int
    breach_limit: float = math.nan
    first_unbalanced: int = -1

    @property
    def kept(self) -> bool:
        """Whether every recorded torque is known and within its limit and the allowance.

        A sample where the grasps cannot hold the load has no torque: it is not kept.
        """
        return self.breach_sample < 0 and self.unbalanced == 0

    def as_dict(self) -> dict[str, object]:
        """JSON-ready."""
        return {"ratio_max": self.ratio, "worst_joint": self.joint,
                "worst_sample": self.sample, "torque_at_worst_N_m": self.peak,
                "limit_at_worst_N_m": self.limit, "allowance_rtol": self.allowance_rtol,
                "enforced": self.enforced, "kept": self.kept,
                "first_breach_sample": self.breach_sample if self.breach_sample >= 0 else None,
                "first_breach_joint": self.breach_joint or None,
                "unbalanced_samples": self.unbalanced,
                "model": "quasi-static: g(q) + J^T w, the arms' link inertias and the "
                         "hands' shares of the load (minimum-norm split), each hand's "
                         "moment moved from its grasp point to its tool point (J's point)"}


def _names(controller: DualArmController) -> list[str]:
    lay = controller.layout
    return list(lay.names[:lay.n_l + lay.n_f])


def record_torques(controller: DualArmController, trace: Trace) -> TorqueReport | None:
    """Compute every recorded sample's joint torques into ``trace``; the report.

    Only for a task with a load or a run with torque limits (None otherwise: the trace
    keeps NaN). The hands' wrenches are read from the trace: call
    :func:`~dualarm_qp.control.loads.record_loads` first.
    """
    task, opts = controller.task, controller.options
    if task.load is None and not opts.torque_limits:
        return None
    statics = LoadTorques(task)
    n_l = task.leader.n
    n = len(trace)
    tau = np.full((n, n_l + task.follower.n), np.nan)
    unbalanced, first_unbalanced = 0, -1
    # The hands' wrenches are the trace's (record_loads wrote them): the same split, the
    # moments about the grasp points, which are posed again here.
    no_load = np.zeros(6)
    sliding_leader = task.leader_surface is not None
    for k in range(n):
        w_l, w_f = ((no_load, no_load) if task.load is None
                    else (trace.f_leader[k], trace.f_follower[k]))
        if not (np.isfinite(w_l).all() and np.isfinite(w_f).all()):
            unbalanced += 1  # the grasps cannot hold the load here
            first_unbalanced = k if first_unbalanced < 0 else first_unbalanced
            continue
        c_l = c_f = None
        if task.load is not None:
            sigma_l = float(trace.grasp_leader[k]) if sliding_leader else 0.0
            hands, _ = hand_statics(task, trace.q_l[k], float(trace.grasp[k]), sigma_l)
            c_l, c_f = hands[0].point, hands[1].point
        tau[k, :n_l] = statics.leader.torque(trace.q_l[k], w_l, c_l)
        tau[k, n_l:] = statics.follower.torque(trace.q_f[k], w_f, c_f)
    trace.tau_leader[:] = tau[:, :n_l]
    trace.tau_follower[:] = tau[:, n_l:]
    limit = joint_torque_limits(controller)
    names = _names(controller)
    limited = np.isfinite(limit)
    ratio, joint, sample, peak, lim = math.nan, "", -1, math.nan, math.nan
    breach, breach_joint, breach_limit = -1, "", math.nan
    if limited.any() and n and np.isfinite(tau).any():
        r = np.where(limited, np.abs(tau) / np.where(limited, limit, 1.0), 0.0)
        r = np.where(np.isnan(r), -np.inf, r)
        flat = int(np.argmax(r))
        k, j = divmod(flat, r.shape[1])
        ratio, joint, sample = float(r[k, j]), names[j], k
        peak, lim = float(tau[k, j]), float(limit[j])
        over = np.argwhere(r > 1.0 + TORQUE_RTOL)
        if over.size:
            breach, breach_joint = int(over[0, 0]), names[int(over[0, 1])]
            breach_limit = float(limit[int(over[0, 1])])
    return TorqueReport(ratio, joint, sample, peak, lim, TORQUE_RTOL, opts.torque_limits,
                        breach, breach_joint, unbalanced, breach_limit, first_unbalanced)


@dataclass(frozen=True)
class TorqueAtStart:
    """A joint beyond its torque limit at the start."""

    joint: str
    torque: float
    limit: float

    @property
    def message(self) -> str:
        """One line for a person."""
        return (f"joint {self.joint} needs {self.torque:.4g} N m to hold the arm and its "
                f"share of the load at the start, beyond its limit of {self.limit:.4g} N m "
                f"({abs(self.torque) / self.limit:.3g}x): a lighter load, another start or "
                "a stronger arm (tau_max)")


def torque_at_start(controller: DualArmController, state: DualArmState
                    ) -> TorqueAtStart | None:
    """Return the worst joint beyond its limit at ``state`` (None: all within, or limits off)."""
    if not controller.options.torque_limits:
        return None
    limit = joint_torque_limits(controller)
    if not controller.hard_bounds:  # the leader's own limits are not imposed
        limit[:controller.layout.n_l] = np.inf
    try:
        tau = LoadTorques(controller.task).torques(state.q_l, state.q_f, state.sigma,
                                                   state.sigma_leader)
    except DualArmError:  # the grasps cannot hold the load here: the first step says so
        return None
    with np.errstate(invalid="ignore"):
        r = np.abs(tau) / limit
    j = int(np.argmax(r))
    if not r[j] > 1.0:
        return None
    return TorqueAtStart(_names(controller)[j], float(tau[j]), float(limit[j]))


def blocked_by_torque(controller: DualArmController, trace: Trace, failure: Failure
                      ) -> Failure:
    """Return ``failure`` as criterion ``"torque"`` when a torque row stops the task.

    The failure's sample is posed again: when its largest feasible task scale is below
    :data:`BLOCKED_SCALE` and torque rows block it, the message names the joints and
    their torques there. Otherwise ``failure`` is returned unchanged.
    """
    if not controller.options.torque_limits or not len(trace):
        return failure
    k = min(failure.sample, len(trace) - 1)
    state = trace.state(k)
    try:
        problem = controller.builder.build(state).problem
        tau = LoadTorques(controller.task).torques(state.q_l, state.q_f, state.sigma,
                                                   state.sigma_leader)
    except DualArmError:
        return failure
    whole = max_task_scale(problem, cap=1.0)
    if whole.scale is not None and whole.scale >= BLOCKED_SCALE:
        return failure
    joints = list(dict.fromkeys(label[len(ROW_PREFIX):].split()[0] for label in whole.blocking
                                if label.startswith(ROW_PREFIX)))
    if not joints:
        return failure
    names = _names(controller)
    limit = joint_torque_limits(controller)
    parts = [f"{j} at {tau[names.index(j)]:.4g} N m (limit {limit[names.index(j)]:.4g})"
             for j in joints]
    worst = max(joints, key=lambda j: abs(tau[names.index(j)]) / limit[names.index(j)])
    i = names.index(worst)
    return dataclasses.replace(
        failure, criterion="torque", amount=float(tau[i]), limit=float(limit[i]),
        message=f"{failure.message}; blocked by a joint torque limit: joint "
                f"{', '.join(parts)} stops the path (the load is beyond the arm there)")
