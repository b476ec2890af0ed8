"""The start of an experiment: both arms' initial joints, and the follower's base from them.

The leader starts at ``D(t0) H1^-1`` and the follower on the grasp ``D(t0)
H2(grasp_initial)``: joints given in the file are checked against those poses (within
:data:`START_TOLERANCE`, or the run's tolerance when tighter), joints not given are
solved (by the PUMA 560's IK branch or from ``near`` joints). With ``base: auto`` the
follower's base is recovered from its initial joints instead (the paper's case).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from ..errors import ConfigError, DualArmError
from ..kinematics.arm import SerialArm
from ..kinematics.ik import ik_dls
from ..kinematics.puma_ik import ik_branch, puma560_ik
from ..task.scene import DualArmTask
from ..task.surfaces import GraspSurface
from ..task.trajectory import Trajectory
from .config import ExperimentConfig, InitialSpec
from .setup_checks import check_within_reach
from .setup_values import Scales, at_key, file_pose, required, vector

#: A start further than this from its pose at t0 (leader: D(t0) H1^-1; follower: the
#: grasp closure) is an error in the file: [m] and [rad] (1 mm, 0.1 deg), or the run's
#: own tolerance (``closure_tolerance`` / ``tracking_tolerance``) when that is tighter.
START_TOLERANCE = (1e-3, math.radians(0.1))

FloatArray = NDArray[np.float64]


def follower_base(cfg: ExperimentConfig, sc: Scales, follower: SerialArm,
                  trajectory: Trajectory, surface: GraspSurface, sigma0: float, path: str,
                  notes: dict[str, Any]) -> tuple[FloatArray, FloatArray | None]:
    """Return the follower's base pose, and its initial joints when they placed the base.

    With ``base: auto`` the base is where the initial joints put the tool on the grasp
    ``D(t0) H2(sigma0)`` (noted in ``notes``); otherwise it is the file's.
    """
    f_spec = cfg.follower
    if f_spec.base != "auto":
        with at_key("follower.base", path):
            return file_pose(f_spec.base, sc), None
    if f_spec.initial.joints is None:
        form = "ik_branch" if f_spec.initial.ik_branch is not None else "near"
        raise ConfigError(f"with 'base: auto' the base is recovered from the initial "
                          f"joints, so a pose to solve ({form}) is ambiguous: give "
                          "'joints', or give the follower's base explicitly",
                          path=path, key=f"follower.initial.{form}",
                          valid=["joints"])
    q_f0 = vector(f_spec.initial.joints, sc.angle, follower.n, "follower.initial.joints", path)
    with at_key("follower.initial.joints", path):
        T_base_tool = follower.fk(q_f0)
        base_f = trajectory.pose(trajectory.t0) @ surface.pose(sigma0) @ np.linalg.inv(
            T_base_tool)
    notes["follower_base_m"] = base_f[:3, 3].tolist()
    notes["follower_base_rotation"] = base_f[:3, :3].round(12).tolist()
    return base_f, q_f0


def _pose_gap(T_a: FloatArray, T_b: FloatArray) -> tuple[float, float]:
    """Return the distance [m] and the angle [rad] between two poses."""
    dp = float(np.linalg.norm(T_a[:3, 3] - T_b[:3, 3]))
    dw = float(np.linalg.norm(pin.log3(T_a[:3, :3] @ T_b[:3, :3].T)))
    return dp, dw


def _start_limit(run_tolerance: tuple[float, float]) -> tuple[float, float]:
    """Return :data:`START_TOLERANCE`, or the run's tolerance where that is tighter."""
    return (min(START_TOLERANCE[0], run_tolerance[0]),
            min(START_TOLERANCE[1], run_tolerance[1]))


def _gap_text(dp: float, dw: float, limit: tuple[float, float]) -> str:
    """Say how far a start is off its pose, and what is allowed."""
    return (f"{dp * 1e3:.3f} mm and {math.degrees(dw):.3f} deg (allowed: "
            f"{limit[0] * 1e3:g} mm, {math.degrees(limit[1]):g} deg)")


def _solve_initial(spec: InitialSpec, arm: SerialArm, preset: str | None, T: FloatArray,
                   sc: Scales, role: str, what: str, path: str,
                   notes: dict[str, Any]) -> FloatArray:
    """Return joints reaching ``T`` by the IK branch or from the ``near`` joints of ``spec``."""
    if spec.ik_branch is not None:
        b = spec.ik_branch
        key = f"{role}.initial.ik_branch"
        if preset != "puma560":
            raise ConfigError("ik_branch needs the puma560 preset; give 'joints' or 'near' "
                              "for other arms", path=path, key=key, valid=["joints", "near"])
        try:
            sol = ik_branch(arm, T, b.arm, b.elbow, b.wrist)
        except DualArmError as err:
            try:
                found = puma560_ik(arm, T)
            except DualArmError:
                found = []
            valid = [f"arm={s.arm} elbow={s.elbow} wrist={s.wrist}" for s in found]
            raise ConfigError(f"the {role}'s IK branch is not valid at {what}: {err}",
                              path=path, key=key, valid=valid) from None
        notes[f"{role}_ik_branch"] = {"arm": b.arm, "elbow": b.elbow, "wrist": b.wrist}
        q = np.asarray(sol.q, dtype=float)
    else:
        key = f"{role}.initial.near"
        seed = vector(required(spec.near, key, path), sc.angle, arm.n, key, path)
        with at_key(key, path):
            # The limits are not imposed: an arm may start outside its range (Table 2).
            res = ik_dls(arm, T, seed, tol_pos=1e-12, tol_rot=1e-12, max_iter=500,
                         respect_limits=False, raise_on_failure=False)
        if not (res.position_error <= 1e-10 and res.rotation_error <= 1e-10):
            raise ConfigError(f"no joints found near these that reach {what} "
                              f"(best: {res.position_error * 1e3:.3f} mm, "
                              f"{math.degrees(res.rotation_error):.3f} deg away); give "
                              "other joints to start from", path=path, key=key)
        q = np.asarray(res.q, dtype=float)
    notes[f"{role}_q0_deg"] = np.rad2deg(q).round(6).tolist()
    return q


def leader_initial(cfg: ExperimentConfig, task: DualArmTask, sc: Scales, path: str,
                   notes: dict[str, Any], tracking: tuple[float, float],
                   sigma_l0: float) -> FloatArray:
    """Return the leader's initial joints: given (and checked at ``D(t0) H1^-1``) or solved."""
    spec = cfg.leader.initial
    leader = task.leader
    with at_key("trajectory", path):
        T = task.leader_target(task.trajectory.t0, sigma_l0)
    if spec.joints is None:
        return _solve_initial(spec, leader, cfg.leader.preset, T, sc, "leader",
                              "D(t0) H1^-1", path, notes)
    q = np.asarray(vector(spec.joints, sc.angle, leader.n, "leader.initial.joints", path))
    with at_key("leader.initial.joints", path):
        dp, dw = _pose_gap(leader.fk(q), T)
    limit = _start_limit(tracking)
    if not (dp <= limit[0] and dw <= limit[1]):
        raise ConfigError("these joints put the object away from the start of the path "
                          f"D(t0): the leader's tool is off by {_gap_text(dp, dw, limit)}; "
                          "give joints at D(t0) H1^-1, or use 'ik_branch' or 'near'",
                          path=path, key="leader.initial.joints")
    return q


def follower_initial(cfg: ExperimentConfig, task: DualArmTask, sc: Scales, path: str,
                     notes: dict[str, Any], q_l0: FloatArray, sigma0: float,
                     closure: tuple[float, float], sigma_l0: float) -> FloatArray:
    """Return the follower's joints with an explicit base: given (and checked) or solved."""
    spec = cfg.follower.initial
    follower = task.follower
    with at_key("object.grasp_initial", path):
        T = task.follower_target(q_l0, sigma0, sigma_l0)
    check_within_reach(cfg, follower, "follower", [
        ("D(t0) H2(grasp_initial) (object.grasp_initial, object.surface, follower.base)", T)],
        path)
    if spec.joints is None:
        return _solve_initial(spec, follower, cfg.follower.preset, T, sc, "follower",
                              "the grasp D(t0) H2(grasp_initial)", path, notes)
    q = np.asarray(vector(spec.joints, sc.angle, follower.n, "follower.initial.joints", path))
    with at_key("follower.initial.joints", path):
        dp, dw = _pose_gap(follower.fk(q), T)
    limit = _start_limit(closure)
    if not (dp <= limit[0] and dw <= limit[1]):
        raise ConfigError("the base and the initial joints do not close the grasp at t0: "
                          "the follower's tool is off the grasp pose D(t0) H2(grasp_initial) "
                          f"by {_gap_text(dp, dw, limit)}; fix the base or the joints, use "
                          "'base: auto', or solve the joints with 'ik_branch' or 'near'",
                          path=path, key="follower.base")
    return q


__all__ = ["START_TOLERANCE", "follower_base", "follower_initial", "leader_initial"]
