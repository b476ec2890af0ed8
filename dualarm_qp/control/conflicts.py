"""Limits in conflict, said plainly: why no step keeps every limit at a state.

When no step meets every limit (the policy cannot scale the task to a feasible step,
or relax it), the solver's message names the bounds and rows in conflict by their
labels (``"qf3 upper (acceleration)"``, ``"clearance follower.link3 - ball"``,
``"torque qf2 max"``; :class:`~dualarm_qp.step.problem.Names`). :func:`plain_causes`
turns the labels whose cause can be read off the state into sentences:

* a collision pair already closer than its safety distance (the pair, the distance);
* a joint torque beyond its limit at this state (the joint, its torque, the limit);
* a joint or grasp outside its range, or whose acceleration limit cannot change its
  rate in one sample to a rate its range (or speed) limit allows (where it is, how fast
  it moves, the limit).

:func:`plainly` puts them in front of a failure's message; the technical detail (the
solver's status and message, the labels) follows.
"""

from __future__ import annotations

import dataclasses
import math
import re
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ..errors import DualArmError
from ..step.limits.collision import ROW_PREFIX as CLEARANCE
from ..step.limits.torque import ROW_PREFIX as TORQUE
from ..step.problem import StepProblem
from ..step.state import DualArmState
from ..task.torques import LoadTorques
from .collisions import pair_distance
from .torques import joint_torque_limits

if TYPE_CHECKING:
    from .controller import DualArmController
    from .failure import Failure

FloatArray = NDArray[np.float64]

#: A bound's label: the variable, the side and the limit that set it.
_BOUND = re.compile(r"^(?P<var>\S+) (?P<side>upper|lower)(?: \((?P<by>.+)\))?$")


def conflict_labels(problem: StepProblem, conflicts: tuple[str, ...] | list[str]
                    ) -> tuple[str, ...]:
    """Return the labels of the limits in conflict, each bound with the limit that set it.

    An empty box (``lower > upper``) is named by its variable alone; its two bounds are
    given here with the limits that set them.
    """
    empty = np.flatnonzero(problem.lower > problem.upper)
    if empty.size:
        return tuple(label for i in empty.tolist() for label in
                     (problem.bound_label(i, False), problem.bound_label(i, True)))
    return tuple(conflicts)


@dataclass(frozen=True)
class Cause:
    """One limit in conflict, in words.

    Attributes
    ----------
    text : str
        The sentence.
    kind : str
        ``"collision"``, ``"torque"`` or ``""`` (a joint's or a grasp's bounds).
    amount, limit : float
        The pair's distance and its safety distance [m], or the joint's torque and its
        limit [N m] (NaN for the bounds).
    """

    text: str
    kind: str = ""
    amount: float = math.nan
    limit: float = math.nan


def plain_causes(controller: DualArmController, state: DualArmState,
                 labels: tuple[str, ...]) -> list[Cause]:
    """Return the causes that ``labels`` name at ``state``, in words.

    Collision pairs first, then torques, then joints and grasps; empty when no label's
    cause can be read off the state (a speed limit against the task, say).
    """
    pairs = [label[len(CLEARANCE):] for label in labels if label.startswith(CLEARANCE)]
    joints = list(dict.fromkeys(label[len(TORQUE):].split()[0] for label in labels
                                if label.startswith(TORQUE)))
    bounds: dict[str, set[str]] = {}
    for label in labels:
        found = _BOUND.match(label)
        if found is not None and not label.startswith((CLEARANCE, TORQUE)):
            bounds.setdefault(found["var"], set()).add(found["by"] or "")
    causes = [_pair(controller, state, p) for p in pairs]
    causes += [_torque(controller, state, j) for j in joints]
    causes += [Cause(text) for var, by in bounds.items()
               if (text := _variable(controller, state, var, by))]
    return causes


def plainly(controller: DualArmController, state: DualArmState, failure: Failure,
            problem: StepProblem | None, conflicts: tuple[str, ...] | list[str]) -> Failure:
    """Return ``failure`` (criterion ``"solver"``) with the plain causes of its conflicts first.

    ``failure.message`` is ``"<where>: <technical detail>"``; the result's is
    ``"<where>: no step keeps every limit: <causes> (<technical detail>; conflicting:
    <labels>)"``. When the first cause is a collision pair or a joint torque, the
    criterion becomes ``"collision"`` or ``"torque"``, with the pair's distance and its
    safety distance or the joint's torque and its limit as amount and limit.
    ``problem`` is the step posed at ``state`` (None: posed again here from the last
    command applied). Unchanged when no cause is known.
    """
    try:
        if problem is None:
            problem = controller.builder.build(state, x_applied=controller.applied).problem
        labels = conflict_labels(problem, conflicts)
        causes = plain_causes(controller, state, labels)
    except DualArmError:  # the state cannot be posed: say nothing more
        return failure
    if not causes:
        return failure
    where, _, detail = failure.message.partition(": ")
    message = (f"{where}: no step keeps every limit: {'; '.join(c.text for c in causes)} "
               f"({detail}; conflicting: {', '.join(labels)})")
    first = causes[0]
    if not first.kind:
        return dataclasses.replace(failure, message=message)
    return dataclasses.replace(failure, criterion=first.kind, amount=first.amount,
                               limit=first.limit, message=message)


def _pair(controller: DualArmController, state: DualArmState, pair: str) -> Cause:
    scene = controller.task.scene
    if scene is None or pair not in scene.pair_names:  # not a pair of the task's scene
        return Cause(f"collision pair {pair} at its safety distance", "collision")
    d = pair_distance(controller, state, scene.pair_names.index(pair))
    d_s = scene.settings.safety_distance
    if d < d_s:
        gap = (f"overlaps by {-d * 1e3:.2f} mm" if d < 0.0
               else f"is already {d * 1e3:.2f} mm apart")
        text = (f"collision pair {pair} {gap}, closer than its safety distance of "
                f"{d_s * 1e3:.3g} mm, and cannot be moved apart as fast as its limit asks")
    else:
        text = f"collision pair {pair} is at its safety distance ({d * 1e3:.2f} mm)"
    return Cause(text, "collision", d, d_s)


def _torque(controller: DualArmController, state: DualArmState, joint: str) -> Cause:
    j = list(controller.layout.names).index(joint)
    limit = float(joint_torque_limits(controller)[j])
    try:
        tau = float(LoadTorques(controller.task).torques(state.q_l, state.q_f, state.sigma,
                                                         state.sigma_leader)[j])
    except DualArmError:  # the grasps cannot hold the load here
        return Cause(f"joint {joint} is at its torque limit of {limit:.4g} N m", "torque",
                     math.nan, limit)
    if abs(tau) > limit:
        text = (f"joint {joint} needs {abs(tau):.4g} N m at this state (to hold its arm and "
                f"its share of the load), beyond its torque limit of {limit:.4g} N m")
    else:
        text = f"joint {joint} holds {abs(tau):.4g} N m, at its torque limit of {limit:.4g} N m"
    return Cause(text, "torque", tau, limit)


def _variable(controller: DualArmController, state: DualArmState, var: str,
              by: set[str]) -> str:
    """Return the plain cause of a joint's or grasp's bounds in conflict ("": none known)."""
    task, lay = controller.task, controller.layout
    i = list(lay.names).index(var)
    if var.startswith(("ql", "qf")):
        arm = task.leader if var.startswith("ql") else task.follower
        k = int(var[2:]) - 1
        who, x, lo, hi, unit = (f"joint {var}", float((state.q_l if arm is task.leader
                                                       else state.q_f)[k]),
                                float(arm.q_min[k]), float(arm.q_max[k]), "rad")
        a_max = float(arm.qdd_max[k])
    else:
        leader = var == "m_l"
        surface = task.leader_surface if leader else task.surface
        if surface is None:
            return ""
        who = "the leader's grasp" if leader else "the follower's grasp"
        x = float(state.sigma_leader if leader else state.sigma)
        lo, hi, unit = float(surface.sigma_min), float(surface.sigma_max), "m"
        a_max = float(controller.options.grasp_acc_max)
    outside = x < lo or x > hi
    ranged = any(b.endswith("range") for b in by)
    if not (outside or "acceleration" in by):
        return ""  # a speed or a range end against the task: no cause of its own
    where = (f"is outside its range ({x:.4g} {unit}; range {lo:.4g} .. {hi:.4g} {unit})"
             if outside else f"is {min(x - lo, hi - x):.3g} {unit} from the end of its range")
    if "acceleration" not in by:
        return f"{who} {where}"
    v = float(controller.applied[i])
    what = "range" if ranged else "speed limit" if any("speed" in b for b in by) else "task"
    return (f"{who} {where} and moves at {v:.3g} {unit}/s: its acceleration limit "
            f"({a_max:.4g} {unit}/s^2, {a_max * controller.options.dt:.3g} {unit}/s per "
            f"sample) cannot bring its rate to one its {what} allows within one sample"
            if math.isfinite(a_max) else f"{who} {where}")


__all__ = ["Cause", "conflict_labels", "plain_causes", "plainly"]
