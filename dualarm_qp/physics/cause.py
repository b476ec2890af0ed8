"""What the simulation saw first: the cause behind a physics verdict.

The verdict (:mod:`.check`) names the worst outcome of the closed loop; this module
finds *when* each outcome began and which came first, from the closed loop's log:

``oscillation``
    the joint servos oscillated with a growing amplitude (:mod:`.oscillation`, in each
    arm joint's velocity error at every substep);
``torque``
    a joint torque first passed ``torque_ratio_max`` of its limit (which joint, how
    much);
``squeezed``
    the internal force first passed the rigid replay's peak by ``squeeze_max``;
``slipped``
    a grasp first moved ``slip_max`` from where it was commanded (or a weld's error);
``dropped``
    the object first left ``D(t)`` by ``deviation_max`` or ``rotation_max`` (or a
    support came off by ``slip_max``);
``controller``
    none of these happened before the controller stopped the closed loop: its own
    message says why (a tracking or closure error of its plan, a step it could not
    solve, a waypoint out of reach).

The cause is the earliest event (on the same sample, in the order above: an
oscillation is what makes the hands squeeze and slip, not the other way round).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ..control.plant import NOT_FOLLOWED
from .oscillation import growing_oscillation
from .settings import PhysicsSettings

if TYPE_CHECKING:
    from .simulation import PhysicsRun

#: The causes, in the order that breaks a tie on one sample.
CAUSES = ("oscillation", "torque", "squeezed", "slipped", "dropped", "controller")

#: What the rollout appends to a failure's message to explain it: from the plan's
#: kinematics (:func:`dualarm_qp.control.diagnosis.explain`), or as the plant's
#: (:func:`dualarm_qp.control.plant.not_followed`).
EXPLANATIONS = ("; cause: ", f"; {NOT_FOLLOWED}")


@dataclass(frozen=True)
class Event:
    """An outcome of the simulation and where it began.

    Attributes
    ----------
    kind : str
        One of :data:`CAUSES`.
    sample : int
        The controller sample (row of the log) by whose end it was seen.
    t : float
        When it began [s] (the simulation's time from the first sample).
    message : str
        What was seen, for a person.
    details : dict
        JSON-ready facts (an oscillation's joints and frequency).
    """

    kind: str
    sample: int
    t: float
    message: str
    details: dict[str, Any] = field(default_factory=dict)

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready."""
        return {"kind": self.kind, "sample": self.sample, "t_s": self.t,
                "message": self.message, **self.details}


def oscillation_event(run: PhysicsRun) -> Event | None:
    """Return the growing oscillation of the run's joint servos, or None.

    Each arm joint's velocity error (``qd - qd_ref`` at every substep) is searched
    (:func:`~dualarm_qp.physics.oscillation.growing_oscillation`); the event starts
    where the first joint's oscillation starts, and names the joint whose velocity
    error grew largest.
    """
    error = run.velocity_error
    if error.ndim != 2 or error.shape[0] == 0:
        return None
    found = {j: o for j in range(error.shape[1])
             if (o := growing_oscillation(error[:, j], run.substep)) is not None}
    if not found:
        return None
    first = min(found, key=lambda j: found[j].start)
    largest = max(found, key=lambda j: found[j].peak)
    o, big = found[first], found[largest]
    name = run.joint_name
    sample, t = _substep_time(run, o.start)
    _, t_big = _substep_time(run, big.peak_index)
    others = len(found) - 1
    message = (f"the joint servos oscillated at {o.frequency_hz:.0f} Hz with a growing "
               f"amplitude from t = {t:.3f} s (sample {sample}, first at {name(first)}): "
               f"the velocity error of {name(largest)} grew to {big.peak:.3g} rad/s by "
               f"t = {t_big:.3f} s" + (f" ({others} other joints oscillating too)"
                                        if others else ""))
    details = {"joints": [name(j) for j in sorted(found, key=lambda j: found[j].start)],
               "frequency_hz": o.frequency_hz, "growth": o.growth, "cycles": o.cycles,
               "largest_joint": name(largest), "largest_velocity_error": big.peak,
               "largest_t_s": t_big}
    return Event("oscillation", sample, t, message, details)


def _substep_time(run: PhysicsRun, i: int) -> tuple[int, float]:
    """Return the sample substep ``i`` moves towards (the row at its end) and its time [s]."""
    k = i // run.substeps
    t = run.log["t"]
    start = float(t[min(k, t.size - 1)])
    return min(k + 1, t.size - 1), start + (i % run.substeps + 1) * run.substep


def threshold_events(run: PhysicsRun, base_internal: float, settings: PhysicsSettings
                     ) -> list[Event]:
    """Return where each threshold of the verdict was first passed (none passed: [])."""
    g, s = run.log, settings
    events = []

    def first(values: Any, limit: float) -> int | None:
        over = np.flatnonzero(np.nan_to_num(np.asarray(values, dtype=float)) > limit)
        return int(over[0]) if over.size else None

    def at(k: int) -> str:
        return f"t = {float(g['t'][k]):.3f} s (sample {k})"

    for key, what, limit, scale, unit, name in (
            ("deviation_pos", "the object left D(t)", s.deviation_max, 1e3, "mm",
             "deviation_max"),
            ("deviation_rot", "the object turned off D(t)", s.rotation_max, 1.0, "rad",
             "rotation_max"),
            ("gap", "the support came off the object", s.slip_max, 1e3, "mm", "slip_max")):
        k = first(g[key], limit)
        if k is not None:
            events.append(Event("dropped", k, float(g["t"][k]),
                                f"{what} at {at(k)}: {g[key][k] * scale:.3g} {unit} "
                                f"({name} {limit * scale:g} {unit})"))
    for key, what in (("slip", "the follower's grasp slipped"),
                      ("weld_leader", "the leader's hand came off its grasp"),
                      ("weld_follower", "the follower's hand came off its grasp")):
        k = first(g[key], s.slip_max)
        if k is not None:
            events.append(Event("slipped", k, float(g["t"][k]),
                                f"{what} at {at(k)}: {g[key][k] * 1e3:.3g} mm (slip_max "
                                f"{s.slip_max * 1e3:g} mm)"))
    k = first(g["torque_ratio_peak"], s.torque_ratio_max)
    if k is not None:
        events.append(_torque_event(run, k, at(k)))
    k = first(np.asarray(g["internal"]) - base_internal, s.squeeze_max)
    if k is not None:
        events.append(Event("squeezed", k, float(g["t"][k]),
                            f"the hands squeezed the object from {at(k)}: internal force "
                            f"{g['internal'][k]:.1f} N, {g['internal'][k] - base_internal:.1f}"
                            f" N above the rigid replay's peak (squeeze_max "
                            f"{s.squeeze_max:g} N)"))
    return events


def _torque_event(run: PhysicsRun, k: int, where: str) -> Event:
    """Return the torque event at sample ``k``: the joint over its limit, by how much."""
    peak = np.asarray(run.log["torque_peak"][k], dtype=float)
    limits = np.r_[run.limits["leader"], run.limits["follower"]]
    ratio = np.where(np.isfinite(limits), peak / limits, 0.0)
    j = int(np.argmax(ratio))
    return Event("torque", k, float(run.log["t"][k]),
                 f"{run.joint_name(j)} passed its torque limit at {where}: "
                 f"{peak[j]:.4g} N m, {ratio[j]:.3g} of its {limits[j]:.4g} N m",
                 {"joint": run.joint_name(j), "torque_N_m": float(peak[j]),
                  "ratio": float(ratio[j])})


def first_cause(events: list[Event]) -> Event | None:
    """Return the earliest event (a tie on one sample: in :data:`CAUSES` order)."""
    if not events:
        return None
    return min(events, key=lambda e: (e.sample, CAUSES.index(e.kind)))


def stop_message(message: str, *, seen: bool) -> str:
    """Return the controller's stop message, unexplained when the simulation saw why.

    The rollout explains a tracking or closure failure from the plan's kinematics
    (e.g. a second-order error of one step) or says the plant did not follow; when the
    simulation itself saw what went wrong first, that explanation is left out.
    """
    if seen:
        for marker in EXPLANATIONS:
            message = message.split(marker, 1)[0]
    return message


__all__ = ["CAUSES", "Event", "first_cause", "oscillation_event", "stop_message",
           "threshold_events"]
