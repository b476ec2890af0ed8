"""The load each hand carries along a run, from the recorded joints and grasps.

For a task with a load (:attr:`DualArmTask.load <dualarm_qp.task.scene.DualArmTask>`),
:func:`record_loads` poses every recorded sample again, builds what each hand can
transmit there (:mod:`dualarm_qp.task.loads`) and splits the object's weight between
them: the trace's ``f_leader`` and ``f_follower`` (world frame, the wrench the hand
applies to the object ``[f; m]`` in [N, N m], moments about the hand's grasp point) and
a :class:`LoadReport` for ``summary.json`` (``loads``). Quasi-static: the object's
acceleration is not counted.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import SupportLostError
from ..task.hands import hand_statics, hand_wrenches
from ..task.loads import UnbalancedLoadError
from ..task.scene import DualArmTask
from .trace import Trace

FloatArray = NDArray[np.float64]

__all__ = ["LoadReport", "hand_statics", "hand_wrenches", "record_loads"]

#: How the split is named in ``summary.json``.
SPLIT_RULE = ("minimum norm of sum(|f|^2 + |m|^2 / L^2) over both hands, L the distance "
              "between the grasp points (zero internal force)")


def _peak(wrench: FloatArray, part: slice) -> tuple[float, int]:
    norms = np.linalg.norm(wrench[:, part], axis=1)
    if not np.isfinite(norms).any():
        return math.nan, -1
    k = int(np.nanargmax(norms))
    return float(norms[k]), k


@dataclass(frozen=True)
class LoadReport:
    """The recorded run's loads, for ``summary.json`` (``loads``).

    Attributes
    ----------
    mass, mass_centre, gravity
        The load [kg; m, object coordinates; m/s^2, world].
    peaks : dict
        Per hand (``"leader"``, ``"follower"``): the largest force [N] and moment
        [N m] magnitudes and the samples where they occur.
    unbalanced : list of int
        Samples where the grasps could not hold the load, or a support would pull (their
        wrench columns are NaN).
    internal : int
        Dimension of the internal wrenches at the first sample (0: statically
        determinate).
    """

    mass: float
    mass_centre: FloatArray
    gravity: FloatArray
    peaks: dict[str, dict[str, float | int]]
    unbalanced: list[int]
    internal: int

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready."""
        return {"mass_kg": self.mass, "mass_centre_m": self.mass_centre.tolist(),
                "gravity_world_m_s2": self.gravity.tolist(),
                "frame": "world; the wrench each hand applies to the object, moment about "
                         "the hand's grasp point; quasi-static",
                "split": SPLIT_RULE, "internal_dimensions": self.internal,
                **self.peaks,
                "unbalanced_samples": len(self.unbalanced),
                "first_unbalanced_sample": self.unbalanced[0] if self.unbalanced else None}

    def warning(self) -> str | None:
        """Return what to tell when some samples could not be balanced (None: all were)."""
        if not self.unbalanced:
            return None
        return (f"the grasps cannot hold the load at {len(self.unbalanced)} samples "
                f"(first: sample {self.unbalanced[0]}): their wrench columns are NaN")


def record_loads(task: DualArmTask, trace: Trace) -> LoadReport | None:
    """Compute every recorded sample's hand wrenches into ``trace``; the report.

    Returns None (and leaves the trace's NaN) for a task without a load.
    """
    load = task.load
    if load is None:
        return None
    n = len(trace)
    out = np.full((n, 2, 6), np.nan)
    unbalanced, internal = [], -1
    sliding_leader = task.leader_surface is not None
    for k in range(n):
        sigma_l = float(trace.grasp_leader[k]) if sliding_leader else 0.0
        try:
            split = hand_wrenches(task, trace.q_l[k], float(trace.grasp[k]), sigma_l)
        except (UnbalancedLoadError, SupportLostError):
            unbalanced.append(k)
            continue
        out[k] = split.wrenches
        if internal < 0:
            internal = split.internal
    trace.f_leader[:] = out[:, 0]
    trace.f_follower[:] = out[:, 1]
    peaks: dict[str, dict[str, float | int]] = {}
    for role, w in (("leader", out[:, 0]), ("follower", out[:, 1])):
        f, kf = _peak(w, slice(0, 3))
        m, km = _peak(w, slice(3, 6))
        peaks[role] = {"force_max_N": f, "force_max_sample": kf,
                       "moment_max_N_m": m, "moment_max_sample": km}
    return LoadReport(load.mass, load.mass_centre, load.gravity, peaks, unbalanced,
                      max(internal, 0))
