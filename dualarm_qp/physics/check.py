"""The physics check of a run: the rigid replay, the closed loop, and the verdict.

* The **rigid replay** drives the arms' servos through the recorded joints (each
  sample's reference is the recorded one, the rates between samples the feed-forward):
  what the plan itself does to the object in a compliant, dynamic world. Its internal
  force is the **baseline**: the absolute level depends on the welds' softness and the
  servo gains, so the squeeze is judged relative to it.
* The **closed loop** runs the controller against the simulator at the controller's
  ``dt`` (:func:`~dualarm_qp.control.rollout.rollout` with a
  :class:`~dualarm_qp.physics.plant.MujocoPlant`): it measures the joints and the sliding
  coordinate from MuJoCo (optionally some samples late) and sends its rates back.

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
import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..control.rollout import RunLimits, rollout
from ..experiments.setup import Experiment
from ..step.state import DualArmState
from .cause import Event, first_cause, oscillation_event, stop_message, threshold_events
from .compliant import compliant_experiment
from .plant import MujocoPlant
from .settings import PhysicsSettings
from .simulation import PhysicsRun

FloatArray = NDArray[np.float64]

#: The verdicts, worst first.
STATUSES = ("dropped", "stopped", "slipped", "torque", "squeezed", "ok")


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
    plant = MujocoPlant(exp.task, settings, delay=0, arm_tau_max=arm_tau_max(exp))
    sl = np.zeros_like(grasp) if grasp_leader is None else np.nan_to_num(grasp_leader)
    dt = float(t[1] - t[0]) if t.size > 1 else exp.options.dt
    plant.reset(DualArmState(float(path_t[0]), q_l[0], q_f[0], float(grasp[0]), float(sl[0])),
                dt)
    for k in range(t.size - 1):
        kf, kf1 = max(k - lag_follower, 0), max(k + 1 - lag_follower, 0)
        h = float(t[k + 1] - t[k])
        plant.replay_step(np.r_[q_l[k], q_f[kf]], np.r_[q_l[k + 1], q_f[kf1]], h,
                          float(path_t[k + 1]), float(grasp[kf1]))
    return PhysicsRun.of("replay", plant, t0)


def closed_loop(exp: Experiment, settings: PhysicsSettings, *, delay: int | None = None
                ) -> PhysicsRun:
    """Run the controller against MuJoCo (the run starts at rest).

    ``delay`` [samples] overrides ``settings.delay``.

    The run's tracking and closure tolerances are widened to the check's thresholds
    (:func:`closed_loop_limits`): the controller goes on while the verdict's thresholds
    hold, and the verdict judges the run.
    """
    t0 = time.perf_counter()
    plant = MujocoPlant(exp.task, settings, delay=delay, arm_tau_max=arm_tau_max(exp))
    exp = compliant_experiment(exp, plant)
    result = rollout(exp.controller(), exp.initial, duration=exp.duration,
                     limits=closed_loop_limits(exp.limits, settings), plant=plant,
                     stop_on_interrupt=True)
    if not plant.log:  # refused before its first sample (the preflight): record the start
        plant.reset(exp.initial, exp.options.dt)
    return PhysicsRun.of("closed_loop", plant, t0, result)


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


@dataclass(frozen=True)
class Verdict:
    """The verdict of the closed loop and what the simulation saw first.

    Attributes
    ----------
    status : str
        One of :data:`STATUSES`.
    reasons : list of str
        Every reason found, not only the worst's (empty when ``ok``).
    cause : Event or None
        What began first (:func:`~dualarm_qp.physics.cause.first_cause`); ``controller``
        when the controller stopped the loop before the simulation passed a threshold
        or oscillated; None when ``ok``.
    oscillation : Event or None
        A growing oscillation of the servos, also when it passed no threshold.
    message : str
        One line: the cause, then what it led to ("" when ``ok``).
    """

    status: str
    reasons: list[str]
    cause: Event | None
    oscillation: Event | None
    message: str


def diagnose(closed: PhysicsRun, baseline: PhysicsRun | None, settings: PhysicsSettings
             ) -> Verdict:
    """Judge the closed loop (:data:`STATUSES`) and find what the simulation saw first.

    Without a baseline (a run that recorded fewer than two samples) the squeeze is
    judged against zero.
    """
    base_internal = 0.0 if baseline is None else baseline.summary()["internal_force_max_N"]
    oscillation = oscillation_event(closed)
    seen = threshold_events(closed, base_internal, settings)
    cause = first_cause(seen + ([] if oscillation is None else [oscillation]))
    reasons = _reasons(closed, base_internal, settings, seen=cause is not None)
    if not reasons:
        return Verdict("ok", [], None, oscillation, "")
    status = min(reasons, key=lambda r: STATUSES.index(r[0]))[0]
    texts = [text for _, text in reasons]
    if oscillation is not None:
        texts.insert(0, oscillation.message)
    if cause is None:  # only the controller's stop: the simulation saw nothing go wrong
        failure = None if closed.result is None else closed.result.failure
        last = closed.log["t"].size - 1
        sample, t = ((failure.sample, failure.t) if failure is not None
                     else (last, float(closed.log["t"][last])))
        cause = Event("controller", sample, t, texts[0])
        return Verdict(status, texts, cause, oscillation, cause.message)
    led_to = next(text for kind, text in reasons if kind == status)
    message = cause.message
    if status == "stopped":
        message += f"; then {led_to}"
    elif status != cause.kind:
        message += f"; then: {led_to}"
    return Verdict(status, texts, cause, oscillation, message)


def _reasons(closed: PhysicsRun, base_internal: float, settings: PhysicsSettings, *,
             seen: bool) -> list[tuple[str, str]]:
    """Every (status, reason) of the closed loop's peaks.

    ``seen``: the simulation saw something go wrong; a stop of the controller is then
    told without its explanation from the plan's kinematics.
    """
    c = closed.summary()
    reasons: list[tuple[str, str]] = []
    if closed.result is not None and not closed.result.completed:
        reasons.append(("stopped", "the controller stopped the closed loop: "
                        + stop_message(closed.result.message, seen=seen)))
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
        worst = c["torque_ratio_worst"]
        reasons.append(("torque", f"a joint torque reached {c['torque_ratio_max']:.3g} of "
                        f"its limit ({worst['joint']} at t = {worst['t_s']:.3f} s; "
                        f"torque_ratio_max {settings.torque_ratio_max:g})"))
    excess = c["internal_force_max_N"] - base_internal
    if excess > settings.squeeze_max:
        reasons.append(("squeezed", f"the internal force peaked at "
                        f"{c['internal_force_max_N']:.1f} N, {excess:.1f} N above the rigid "
                        f"replay's (squeeze_max {settings.squeeze_max:g} N)"))
    return reasons


def verdict(closed: PhysicsRun, baseline: PhysicsRun | None, settings: PhysicsSettings
            ) -> tuple[str, list[str]]:
    """Return the status (:data:`STATUSES`) of the closed loop and every reason found.

    The status and reasons of :func:`diagnose`.
    """
    judged = diagnose(closed, baseline, settings)
    return judged.status, judged.reasons


def physics_summary(closed: PhysicsRun, baseline: PhysicsRun | None,
                    settings: PhysicsSettings) -> dict[str, Any]:
    """Return the ``physics`` section of ``summary.json`` (``replay`` None without one)."""
    judged = diagnose(closed, baseline, settings)
    c = closed.summary()
    b = None if baseline is None else baseline.summary()
    cause = judged.cause
    if "message" in c and cause is not None and cause.kind != "controller":
        c["message"] = stop_message(c["message"], seen=True)  # the simulation saw why
    # Each simulation with what it saw first (the replay is the squeeze's baseline).
    c["cause"] = None if cause is None else cause.as_dict()
    if b is not None and baseline is not None:
        first = first_cause(threshold_events(baseline, math.inf, settings))
        b["cause"] = None if first is None else first.as_dict()
    return {
        "status": judged.status, "reasons": judged.reasons,
        "cause": None if cause is None else cause.kind,
        "cause_sample": None if cause is None else cause.sample,
        "cause_t_s": None if cause is None else cause.t,
        "message": judged.message,
        "oscillation": None if judged.oscillation is None else judged.oscillation.as_dict(),
        "internal_force_excess_N": c["internal_force_max_N"] - (
            0.0 if b is None else b["internal_force_max_N"]),
        "settings": settings.as_dict(),
        "servo_gains": closed.gains,
        "torque_limits_N_m": {k: [float(x) if np.isfinite(x) else None for x in v]
                              for k, v in closed.limits.items()},
        "model_notes": closed.notes,
        "replay": b, "closed_loop": c,
    }


__all__ = ["STATUSES", "PhysicsRun", "Verdict", "closed_loop", "closed_loop_limits",
           "diagnose", "physics_summary", "replay", "verdict"]
