"""One simulation of a run in MuJoCo (:class:`PhysicsRun`): its log, its peaks, its rollout."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..control.rollout import RolloutResult
from .plant import MujocoPlant
from .settings import SUBSTEP

FloatArray = NDArray[np.float64]


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
    worst : tuple of (float, str, float)
        The largest torque ratio, its joint (``leader.<joint>``) and its time [s].
    joints : list of str
        The arm joints, ``leader.<joint>`` then ``follower.<joint>``.
    velocity_error : ndarray, shape (substeps, joints)
        Each arm joint's ``qd - qd_ref`` at every substep [rad/s]
        (:attr:`MujocoPlant.velocity_error
        <dualarm_qp.physics.plant.MujocoPlant.velocity_error>`).
    substep : float
        The simulator's time step [s].
    substeps : int
        Substeps per controller sample.
    gains : dict or None
        The servos' gains (:meth:`ServoGains.as_dict
        <dualarm_qp.physics.gains.ServoGains.as_dict>`).
    """

    name: str
    log: dict[str, FloatArray]
    wall_s: float
    notes: list[str]
    limits: dict[str, FloatArray]
    result: RolloutResult | None = None
    worst: tuple[float, str, float] = (0.0, "", 0.0)
    joints: list[str] = field(default_factory=list)
    velocity_error: FloatArray = field(default_factory=lambda: np.zeros((0, 0)))
    substep: float = SUBSTEP
    substeps: int = 1
    gains: dict[str, Any] | None = None

    @classmethod
    def of(cls, name: str, plant: MujocoPlant, started: float,
           result: RolloutResult | None = None) -> PhysicsRun:
        """Return the run ``plant`` simulated since ``started`` (``time.perf_counter``)."""
        names = [f"{role}.{n}" for role, arm in (("leader", plant.task.leader),
                                                  ("follower", plant.task.follower))
                 for n in arm.joint_names]
        ratio, j, t = plant.worst
        error = np.asarray(plant.velocity_error, dtype=float).reshape(-1, len(names))
        return cls(name, plant.arrays(), time.perf_counter() - started, plant.notes,
                   plant.limits, result, (ratio, names[j] if j >= 0 else "", t), names,
                   error, float(plant.model.opt.timestep), plant.substeps,
                   None if plant.gains is None else plant.gains.as_dict())

    def joint_name(self, j: int) -> str:
        """Return the name of arm joint ``j`` (over both arms, the leader's first)."""
        return self.joints[j] if j < len(self.joints) else f"joint {j}"

    def summary(self) -> dict[str, Any]:
        """Peaks of the run (JSON-ready, SI)."""
        g = self.log

        none = np.zeros(0)

        def peak(key: str) -> float:
            v = g.get(key, none)
            return float(np.nanmax(v)) if v.size and not np.isnan(v).all() else float("nan")

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
            "load_share_follower": _span(g.get("share", none)),
            "load_share_follower_planned": _span(g.get("share_plan", none)),
            "split_error_max": peak("split_error"),
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


def _span(values: FloatArray) -> list[float] | None:
    """Return ``[min, max]`` of the finite values (None when there are none)."""
    finite = values[np.isfinite(values)]
    return [float(finite.min()), float(finite.max())] if finite.size else None


__all__ = ["PhysicsRun"]
