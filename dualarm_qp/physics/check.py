"""The physics check of a run: the rigid replay, the closed loop, and the verdict.

* The **rigid replay** drives the arms' servos through the recorded joints (each
  sample's reference is the recorded one, the rates between samples the feed-forward):
  what the plan itself does to the object in a compliant, dynamic world. Its internal
  force is the **baseline**: the absolute level depends on the welds' softness and the
  servo gains, so the squeeze is judged relative to it.
* The **closed loop** runs the controller against the simulator at the controller's
  ``dt`` (:func:`~dualarm_qp.control.rollout.rollout` with a
  :class:`~dualarm_qp.physics.plant.MujocoPlant`): it measures the joints and the sliding
  coordinate from MuJoCo (optionally one sample late) and sends its rates back.

The verdict (:data:`STATUSES`, the first that applies) reads the closed loop:

``dropped``
    the object left ``D(t)`` by more than ``deviation_max`` or turned off it by more
    than ``rotation_max``, or a support came off the object by more than ``slip_max``;
``stopped``
    the closed loop did not carry the task to its end: the controller stopped it (a
    tracking or closure error of the measured state beyond the run's tolerances, a step
    it could not solve; the message says which);
``slipped``
    a grasp moved by more than ``slip_max`` from where it was commanded (the sliding
    coordinate against the controller's, or a weld's own error);
``torque``
    a joint torque passed ``torque_ratio_max`` of its limit;
``squeezed``
    the internal force passed the replay's peak by more than ``squeeze_max``;
``ok``
    none of these.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..control.rollout import RolloutResult, RunLimits, rollout
from ..experiments.setup import Experiment
from ..step.state import DualArmState
from .plant import MujocoPlant
from .settings import PhysicsSettings

FloatArray = NDArray[np.float64]

#: The verdicts, worst first.
STATUSES = ("dropped", "stopped", "slipped", "torque", "squeezed", "ok")


@dataclass
class PhysicsRun:
    """One simulation of a run.

    Attributes
    ----------
    name : {"replay", "closed_loop"}
    log : dict of str to ndarray
        :attr:`MujocoPlant.log <dualarm_qp.physics.plant.MujocoPlant.log>` as arrays.
    wall_s : float
        Wall-clock time [s].
    notes : list of str
        The model's simplifications.
    limits : dict of str to ndarray
        Joint torque limits [N m] per arm.
    result : RolloutResult or None
        The closed loop's rollout.
    """

    name: str
    log: dict[str, FloatArray]
    wall_s: float
    notes: list[str]
    limits: dict[str, FloatArray]
    result: RolloutResult | None = None
    worst: tuple[float, str, float] = (0.0, "", 0.0)

    def summary(self) -> dict[str, Any]:
        """Peaks of the run (JSON-ready, SI)."""
        g = self.log

        def peak(key: str) -> float:
            v = g[key]
            return float(np.max(v)) if v.size and not np.isnan(v).all() else float("nan")

        torque = g["torque_peak"]  # each joint's largest |torque| over a sample's substeps
        n_l = len(self.limits["leader"])
        out: dict[str, Any] = {
            "samples": int(g["t"].size), "wall_time_s": self.wall_s,
            "deviation_pos_max_m": peak("deviation_pos"),
            "deviation_rot_max_rad": peak("deviation_rot"),
            "internal_force_max_N": peak("internal"),
            "follower_support_min_N": float(np.min(g["support"])),
            "follower_support_max_N": peak("support"),
            "slip_max_m": peak("slip"),
            "weld_error_max_m": max(peak("weld_leader"), peak("weld_follower")),
            "support_gap_max_m": peak("gap"),
            "torque_ratio_max": peak("torque_ratio_peak"),
            "torque_ratio_worst": {"joint": self.worst[1], "t_s": self.worst[2]},
            "torque_max_N_m": {"leader": np.max(torque[:, :n_l], axis=0).tolist(),
                               "follower": np.max(torque[:, n_l:], axis=0).tolist()},
        }
        if self.result is not None:
            out["completed"] = self.result.completed
            out["message"] = self.result.message
            out["path_completed_pct"] = 100.0 * self.result.path_completed
        return out


def replay(exp: Experiment, settings: PhysicsSettings, t: FloatArray, q_l: FloatArray,
           q_f: FloatArray, path_t: FloatArray, grasp: FloatArray,
           grasp_leader: FloatArray | None = None, *, lag_follower: int = 0) -> PhysicsRun:
    """Drive the recorded joints through MuJoCo (the rigid replay).

    Parameters
    ----------
    t, q_l, q_f, path_t, grasp, grasp_leader
        The recorded samples (``trajectory.csv``): time [s], joints [rad], path time
        [s], grasp coordinates [m].
    lag_follower : int
        Replay the follower this many samples late (a deliberately lagged follower).
    """
    t0 = time.perf_counter()
    plant = MujocoPlant(exp.task, settings, delay=False, arm_tau_max=arm_tau_max(exp))
    sl = np.zeros_like(grasp) if grasp_leader is None else np.nan_to_num(grasp_leader)
    dt = float(t[1] - t[0]) if t.size > 1 else exp.options.dt
    plant.reset(DualArmState(float(path_t[0]), q_l[0], q_f[0], float(grasp[0]), float(sl[0])),
                dt)
    for k in range(t.size - 1):
        kf, kf1 = max(k - lag_follower, 0), max(k + 1 - lag_follower, 0)
        h = float(t[k + 1] - t[k])
        plant.replay_step(np.r_[q_l[k], q_f[kf]], np.r_[q_l[k + 1], q_f[kf1]], h,
                          float(path_t[k + 1]), float(grasp[kf1]))
    return PhysicsRun("replay", plant.arrays(), time.perf_counter() - t0, plant.notes,
                      plant.limits, worst=_worst(plant))


def closed_loop(exp: Experiment, settings: PhysicsSettings, *, delay: bool | None = None
                ) -> PhysicsRun:
    """Run the controller against MuJoCo (the run starts at rest).

    The run's tracking and closure tolerances are widened to the check's thresholds
    (:func:`closed_loop_limits`): the controller goes on while the verdict's thresholds
    hold, and the verdict judges the run.
    """
    t0 = time.perf_counter()
    plant = MujocoPlant(exp.task, settings, delay=delay, arm_tau_max=arm_tau_max(exp))
    result = rollout(exp.controller(), exp.initial, duration=exp.duration,
                     limits=closed_loop_limits(exp.limits, settings), plant=plant,
                     stop_on_interrupt=True)
    if not plant.log:  # refused before its first sample (the preflight): record the start
        plant.reset(exp.initial, exp.options.dt)
    return PhysicsRun("closed_loop", plant.arrays(), time.perf_counter() - t0, plant.notes,
                      plant.limits, result, _worst(plant))


def arm_tau_max(exp: Experiment) -> dict[str, FloatArray | None]:
    """Each arm's configured ``tau_max`` [N m] (None: the model's ``effort``, if any)."""
    return {"leader": exp.options.leader_tau_max, "follower": exp.options.follower_tau_max}


def closed_loop_limits(limits: RunLimits, settings: PhysicsSettings) -> RunLimits:
    """Return the run's limits with tolerances no tighter than the check's thresholds.

    Tracking: ``(deviation_max, rotation_max)``; closure: ``(slip_max, rotation_max)``
    (each the larger of the run's and the threshold).
    """
    return dataclasses.replace(
        limits,
        tracking=(max(limits.tracking[0], settings.deviation_max),
                  max(limits.tracking[1], settings.rotation_max)),
        closure=(max(limits.closure[0], settings.slip_max),
                 max(limits.closure[1], settings.rotation_max)))


def _worst(plant: MujocoPlant) -> tuple[float, str, float]:
    """Return the largest torque ratio, its joint (``leader.<joint>``) and its time [s]."""
    ratio, j, t = plant.worst
    names = [f"{role}.{n}" for role, arm in (("leader", plant.task.leader),
                                              ("follower", plant.task.follower))
             for n in arm.joint_names]
    return ratio, (names[j] if j >= 0 else ""), t


def verdict(closed: PhysicsRun, baseline: PhysicsRun | None, settings: PhysicsSettings
            ) -> tuple[str, list[str]]:
    """Return the status (:data:`STATUSES`) of the closed loop and every reason found.

    Without a baseline (a run that recorded fewer than two samples) the squeeze is
    judged against zero.
    """
    c = closed.summary()
    base_internal = 0.0 if baseline is None else baseline.summary()["internal_force_max_N"]
    reasons: list[tuple[str, str]] = []
    if closed.result is not None and not closed.result.completed:
        reasons.append(("stopped", f"the closed loop stopped: {closed.result.message}"))
    if c["deviation_pos_max_m"] > settings.deviation_max:
        reasons.append(("dropped", f"the object left D(t) by "
                        f"{c['deviation_pos_max_m'] * 1e3:.2f} mm (deviation_max "
                        f"{settings.deviation_max * 1e3:g} mm)"))
    if c["deviation_rot_max_rad"] > settings.rotation_max:
        reasons.append(("dropped", f"the object turned off D(t) by "
                        f"{c['deviation_rot_max_rad']:.3g} rad (rotation_max "
                        f"{settings.rotation_max:g} rad)"))
    if c["support_gap_max_m"] > settings.slip_max:
        reasons.append(("dropped", f"the support came off the object by "
                        f"{c['support_gap_max_m'] * 1e3:.2f} mm"))
    slip = max(c["slip_max_m"], c["weld_error_max_m"])
    if slip > settings.slip_max:
        reasons.append(("slipped", f"a grasp slipped by {slip * 1e3:.2f} mm (slip_max "
                        f"{settings.slip_max * 1e3:g} mm)"))
    if c["torque_ratio_max"] > settings.torque_ratio_max:
        reasons.append(("torque", f"a joint torque reached {c['torque_ratio_max']:.3g} of "
                        f"its limit (torque_ratio_max {settings.torque_ratio_max:g})"))
    excess = c["internal_force_max_N"] - base_internal
    if excess > settings.squeeze_max:
        reasons.append(("squeezed", f"the internal force peaked at "
                        f"{c['internal_force_max_N']:.1f} N, {excess:.1f} N above the rigid "
                        f"replay's (squeeze_max {settings.squeeze_max:g} N)"))
    if not reasons:
        return "ok", []
    worst = min(reasons, key=lambda r: STATUSES.index(r[0]))[0]
    return worst, [text for _, text in reasons]


def physics_summary(closed: PhysicsRun, baseline: PhysicsRun | None,
                    settings: PhysicsSettings) -> dict[str, Any]:
    """Return the ``physics`` section of ``summary.json`` (``replay`` None without one)."""
    status, reasons = verdict(closed, baseline, settings)
    c = closed.summary()
    b = None if baseline is None else baseline.summary()
    return {
        "status": status, "reasons": reasons,
        "internal_force_excess_N": c["internal_force_max_N"] - (
            0.0 if b is None else b["internal_force_max_N"]),
        "settings": settings.as_dict(),
        "torque_limits_N_m": {k: [float(x) if np.isfinite(x) else None for x in v]
                              for k, v in closed.limits.items()},
        "model_notes": closed.notes,
        "replay": b, "closed_loop": c,
    }


__all__ = ["STATUSES", "PhysicsRun", "closed_loop", "closed_loop_limits", "physics_summary",
           "replay", "verdict"]
