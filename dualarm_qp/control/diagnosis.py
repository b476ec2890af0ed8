"""Why the task could not be followed: the cause behind a tracking or closure failure.

A run that fails on ``tracking``, ``closure``, ``stalled`` or ``path_incomplete`` says
where it failed; this module says why, from the step at the state where it failed,
posed at full path speed:

* **speed**: with the speed limits alone, the largest feasible task scale is below 1:
  the limits that stop it are named, with how many times more the full path needs;
  the scale policy slows the path to keep them, and the path cannot be done in time
  or the limits leave too little to correct the errors;
* **range**: the ranges (within one sample) cut the task scale further;
* **collision**: collision pairs at their safety distance cut it (named);
* **workspace edge**: an arm's Jacobian (nearly) loses rank, so the path asks for a
  motion the arm cannot make (its smallest singular value is named);
* **tolerance**: none of the above: one step of ``dt`` at these speeds leaves an error
  of second order that the tolerance does not allow (a smaller ``dt``, a slower path or
  a larger tolerance helps).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from numpy.typing import NDArray

from ..solvers._affine import affine_solutions
from ..solvers._scale import max_task_scale
from ..step.build import StepBuilder
from ..step.limits.collision import ROW_PREFIX
from ..step.state import DualArmState

FloatArray = NDArray[np.float64]

#: An arm whose Jacobian's smallest singular value is below this is at its workspace
#: edge (mixed units: m/rad and rad/rad, as the trace's ``sigma_min``).
WORKSPACE_EDGE = 0.01

#: A largest feasible task scale below this names its limits as a cause.
SPEED_SHARE = 1.0 - 1e-9


def explain(builder: StepBuilder, state: DualArmState, *,
            budget_share: float | None = None, budget: tuple[float, float] | None = None
            ) -> str:
    """Name the causes that keep the task from being followed at ``state``.

    Parameters
    ----------
    builder : StepBuilder
        The controller's step builder (the task, the options and the limits).
    state : DualArmState
        The state where the run failed.
    budget_share : float, optional
        The errors that the step at full path speed would leave at the next sample,
        relative to the controller's error budget (:mod:`.lookahead`); above 1 the
        budget slows the path, and the tolerance is named as a cause.
    budget : tuple of float, optional
        That budget (position [m], rotation [rad]), for the message.

    Returns
    -------
    str
        ``"cause: ..."``, the causes found joined by ``"; "``, and both arms' smallest
        singular values.
    """
    build = builder.build(state)
    problem = build.problem
    causes: list[str] = []
    v = builder.speed_limits
    speeds = max_task_scale(dataclasses.replace(problem, lower=-v, upper=v), cap=1.0)
    if speeds.scale is not None and speeds.scale < SPEED_SHARE:
        over = math.inf if speeds.scale <= 0.0 else 1.0 / speeds.scale
        causes.append(f"speed limits bind ({_names(speeds.blocking)}): the path at full "
                      f"speed needs {over:.3g} times what they allow")
    whole = max_task_scale(problem, cap=1.0)
    if (whole.scale is not None and whole.scale < SPEED_SHARE
            and (speeds.scale is None or whole.scale < speeds.scale * (1.0 - 1e-9))):
        pairs = tuple(b[len(ROW_PREFIX):] for b in whole.blocking if b.startswith(ROW_PREFIX))
        others = tuple(b for b in whole.blocking if not b.startswith(ROW_PREFIX))
        if pairs:
            causes.append(f"collision pairs bind ({_names(pairs)}): they keep their safety "
                          f"distance, and the path can go at {whole.scale:.3g} of its speed "
                          "at most")
        if others or not pairs:
            causes.append(f"range ends bind ({_names(others)}): the path can go at "
                          f"{whole.scale:.3g} of its speed at most")
    edges = [f"workspace edge: the {arm}'s smallest singular value is {sv:.3g} (below "
             f"{WORKSPACE_EDGE:g}: the path asks for a motion it can hardly make)"
             for arm, sv in zip(("leader", "follower"), build.sigma_min, strict=True)
             if sv < WORKSPACE_EDGE]
    causes += edges
    if affine_solutions(problem.A, problem.b) is None and not edges:
        causes.append("the step's equality has no solution (the arms' Jacobians lost "
                      "rank together)")
    if budget_share is not None and budget_share > 1.0 and budget is not None:
        causes.append(f"tolerance: at full speed one step of {builder.options.dt:g} s "
                      f"would leave {budget_share:.3g} times the error budget "
                      f"({budget[0]:g} m, {budget[1]:g} rad, half the tolerance) at the "
                      "next sample: the path is slowed for it (a smaller dt or a larger "
                      "tolerance helps)")
    if not causes:
        causes.append(f"tolerance: one step of {builder.options.dt:g} s at these speeds "
                      "leaves a second-order error beyond the tolerance (a smaller dt, a "
                      "slower path or a larger tolerance helps)")
    sv_l, sv_f = build.sigma_min
    return (f"cause: {'; '.join(causes)} (smallest singular values: leader {sv_l:.3g}, "
            f"follower {sv_f:.3g})")


def _names(labels: tuple[str, ...]) -> str:
    return ", ".join(dict.fromkeys(labels)) or "no single bound"


__all__ = ["WORKSPACE_EDGE", "explain"]
