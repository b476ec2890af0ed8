"""The criteria a run checks at every sample: closure, tracking, singularity, the solver, stall.

Each returns the :class:`~.failure.Failure` of the sample, or None when the sample keeps
the criterion; the loop (:mod:`.run_loop`) stops at the first failure.
"""

from __future__ import annotations

import math

from ..errors import DualArmError, InfeasibleStepError, SupportLostError
from ..step.state import DualArmState
from .conflicts import plainly
from .controller import DualArmController
from .failure import Failure, at
from .run_limits import RunLimits
from .trace import Trace


def sample_failure(tr: Trace, k: int, applied: bool, status: str, message: str,
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
                           f"{at(k, t)}: {what}: {pos:.3g} m, {rot:.3g} rad "
                           f"(tolerance {tol_pos:g} m, {tol_rot:g} rad){hint}")
    threshold = limits.singular_value_min
    if threshold > 0 and limits.singularity_action != "ignore":
        for arm, sv in (("leader", tr.sigma_min_l[k]), ("follower", tr.sigma_min_f[k])):
            if sv < threshold:
                text = (f"{at(k, t)}: the {arm} is near a singularity (smallest singular value "
                        f"of its Jacobian {sv:.3g}, threshold {threshold:g})")
                if limits.singularity_action == "stop":
                    return Failure("singularity", k, t, float(sv), threshold, text)
                if not any(f"the {arm} is near a singularity" in w for w in warnings):
                    warnings.append(f"first at {text}")
    if not applied:
        return Failure("solver", k, t, math.nan, math.nan,
                       f"{at(k, t)}: solver status {status}: {message}")
    return None


def step_failure(controller: DualArmController, state: DualArmState, k: int, t: float,
                 err: DualArmError, message: str) -> Failure:
    """Return the failure of a step that raised ``err`` at sample ``k`` (wall time ``t`` [s]).

    A lost support fails on ``"support"``, any other refusal on ``"solver"``, with
    ``message``; an infeasible step (the ``"stop"`` policy) says why, plainly
    (:func:`.conflicts.plainly`).
    """
    failure = Failure("support" if isinstance(err, SupportLostError) else "solver", k, t,
                      math.nan, math.nan, message)
    if isinstance(err, InfeasibleStepError):
        failure = plainly(controller, state, failure, None, err.conflicts)
    return failure


def stall_failure(tr: Trace, k: int, t: float, tau: float, window: tuple[float, float],
                  message: str) -> Failure | None:
    """Return the failure of a path stalled over ``window``, or None.

    ``window`` holds the wall time [s] and the path time [s] at its start; the path
    stalled when its time advanced by less than 1% of the wall time elapsed since.
    ``message`` is the last solver message.
    """
    elapsed, advanced = t - window[0], tau - window[1]
    if not advanced < 0.01 * elapsed:
        return None
    return Failure(
        "stalled", k, t, advanced, 0.01 * elapsed,
        f"step {k} at t = {t:.4f} s: path stalled: the object advanced "
        f"{advanced:.3g} s along its path in {elapsed:.3g} s (task scale {tr.scale[k]:.3g}; "
        f"smallest singular values: leader {tr.sigma_min_l[k]:.3g}, follower "
        f"{tr.sigma_min_f[k]:.3g}); last solver message: {message}")


__all__ = ["sample_failure", "stall_failure", "step_failure"]
