"""Which limits a run keeps: per arm and grasp, torques and collisions, in one record.

``summary.json`` holds it as ``limits_kept`` and ``dualarm-qp run`` prints it in two
lines before the realised motion, so that a limit a file leaves out (a URDF states no
acceleration limits; a continuous joint has no range) is seen, not assumed:

    limits kept: leader range 6/6, speed 6/6, acceleration 6/6; follower range 3/6 (none:
    qf1, qf4, qf6), speed 6/6, acceleration off
      grasp range, speed, acceleration; torque off; collision off

With jerk limits (``controller.jerk_limits``), each arm and grasp also names ``jerk``
(``jerk 7/7``); without them, and without torque limits, those are left out of the
arms' lists.

For each arm, ``k/n``: ``k`` of its ``n`` joints have that limit (the joints without
one are named); ``off``: the file's ``controller`` setting is off. For each grasp, a
limit is named when it is kept; ``none`` marks one that is on without a value
(``grasp_speed_max`` or ``grasp_acc_max`` not given). A solver that does not claim hard
limits keeps none of them.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..task.torques import torque_limits_of
from .setup import Experiment

FloatArray = NDArray[np.float64]


def limits_kept(exp: Experiment, hard: bool) -> dict[str, Any]:
    """Return the limits the run of ``exp`` keeps (JSON-ready; see the module docstring).

    Parameters
    ----------
    exp : Experiment
        The experiment (its arms, grasps, scene and step options).
    hard : bool
        Whether the solver keeps hard limits (``RolloutResult.hard_bounds``).

    Returns
    -------
    dict
        ``enforced`` (``hard``); ``leader`` and ``follower``: ``{"joints": n, "range",
        "speed", "acceleration", "jerk", "torque"}``, each the list of the joints without
        that limit (``[]``: every joint has one) or None when the setting is off;
        ``grasp`` (and ``grasp_leader`` when it slides): ``{"range", "speed",
        "acceleration", "jerk"}``,
        each True (kept), False (on, no value) or None (off); ``collision``: None when
        off, else ``{"pairs", "safety_distance_m"}``.
    """
    opts, task = exp.options, exp.task
    out: dict[str, Any] = {"enforced": hard}
    for role, arm, prefix, tau in (("leader", task.leader, "ql", opts.leader_tau_max),
                                   ("follower", task.follower, "qf", opts.follower_tau_max)):
        names = [f"{prefix}{j + 1}" for j in range(arm.n)]
        ranged = np.isfinite(arm.q_min) | np.isfinite(arm.q_max)
        out[role] = {
            "joints": arm.n,
            "range": _without(names, ranged),
            "speed": _without(names, np.isfinite(arm.qd_max)) if opts.velocity_limits
            else None,
            "acceleration": _without(names, np.isfinite(arm.qdd_max))
            if opts.acceleration_limits else None,
            "jerk": _without(names, np.isfinite(arm.qddd_max)) if opts.jerk_limits else None,
            # The torque limits were checked when the experiment was built.
            "torque": _without(names, np.isfinite(torque_limits_of(arm, tau, role)))
            if opts.torque_limits else None,
        }
    for key, surface in (("grasp", task.surface), ("grasp_leader", task.leader_surface)):
        if surface is None:
            continue
        out[key] = {
            "range": bool(np.isfinite(surface.sigma_min) or np.isfinite(surface.sigma_max)),
            "speed": bool(np.isfinite(opts.grasp_speed_max)) if opts.velocity_limits
            else None,
            "acceleration": bool(np.isfinite(opts.grasp_acc_max))
            if opts.acceleration_limits else None,
            "jerk": bool(np.isfinite(opts.grasp_jerk_max)) if opts.jerk_limits else None,
        }
    scene = task.scene
    out["collision"] = (None if scene is None or not scene.settings.enabled else
                        {"pairs": len(scene.pairs),
                         "safety_distance_m": scene.settings.safety_distance})
    return out


def _without(names: list[str], limited: NDArray[np.bool_]) -> list[str]:
    return [name for name, on in zip(names, limited.tolist(), strict=True) if not on]


def limits_lines(kept: dict[str, Any]) -> list[str]:
    """Return the console's two lines of :func:`limits_kept`'s record (indented)."""
    if not kept.get("enforced"):
        return ["  limits kept: none (this solver does not enforce limits; the realised "
                "motion is measured against them only)"]
    arms = "; ".join(f"{role} " + ", ".join(_arm_item(kind, kept[role].get(kind),
                                                       kept[role]["joints"])
                                            for kind in ("range", "speed", "acceleration",
                                                         "jerk", "torque")
                                            if kind not in _SHOWN_WHEN_ON
                                            or kept[role].get(kind) is not None)
                     for role in ("leader", "follower"))
    grasps = "; ".join(f"{key.replace('_', ' ')} " + ", ".join(
        _grasp_item(kind, kept[key].get(kind))
        for kind in ("range", "speed", "acceleration", "jerk")
        if kind not in _SHOWN_WHEN_ON or kept[key].get(kind) is not None)
        for key in ("grasp", "grasp_leader") if key in kept)
    torque = "" if kept["leader"]["torque"] is not None else "; torque off"
    c = kept["collision"]
    collision = ("collision off" if c is None else
                 f"collision {c['pairs']} pairs at {c['safety_distance_m'] * 1e3:.3g} mm")
    return [f"  limits kept: {arms}", f"    {grasps}{torque}; {collision}"]


#: Limits the console names only when their setting is on (most runs keep neither).
_SHOWN_WHEN_ON = ("jerk", "torque")


def _arm_item(kind: str, without: list[str] | None, n: int) -> str:
    if without is None:
        return f"{kind} off"
    text = f"{kind} {n - len(without)}/{n}"
    return text + (f" (none: {', '.join(without)})" if without else "")


def _grasp_item(kind: str, kept: bool | None) -> str:
    return kind if kept else f"{kind} {'off' if kept is None else 'none'}"


__all__ = ["limits_kept", "limits_lines"]
