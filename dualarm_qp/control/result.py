"""The outcome of a rollout (:class:`RolloutResult`): its samples, its verdict, its summary."""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..collision.clearance import ClearanceReport
from .failure import Failure
from .realised import LimitReport
from .torques import TorqueReport
from .trace import Trace

FloatArray = NDArray[np.float64]


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
        return time_lost_to_slowing(float(tr.t[-1] - tr.t[0]), float(tr.tau[-1] - tr.tau[0]),
                                    self.dt)

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


def time_lost_to_slowing(elapsed: float, advanced: float, dt: float) -> float:
    """Time lost to slowing [s] when the path time advanced by ``advanced`` [s] in ``elapsed``.

    The elapsed time minus the whole samples of ``dt`` [s] the advance takes at full
    speed: the shortened last sample where the path ends is no loss. Rounded to the
    nanosecond, so that a run that lost no time says 0, not rounding noise.
    """
    return max(round(elapsed - dt * math.ceil(advanced / dt - 1e-9), 9), 0.0)


__all__ = ["RolloutResult", "time_lost_to_slowing"]
