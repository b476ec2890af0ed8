"""Turn a validated :class:`ExperimentConfig` into library objects, in SI units."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, TypeVar

import numpy as np
from numpy.typing import NDArray

from ..control.controller import DualArmController
from ..control.rollout import RunLimits
from ..errors import ConfigError, DualArmError, SolverNotFoundError
from ..kinematics.arm import DHTable, SerialArm
from ..kinematics.puma560 import puma560
from ..kinematics.puma_ik import ik_branch, puma560_ik
from ..se3 import make_pose, rot_x, rot_y, rot_z
from ..solvers.policy import Policy
from ..solvers.registry import SolverInfo, get_solver, solver_info
from ..step.build import DualArmState, StepOptions
from ..task.scene import DualArmTask
from ..task.surfaces import CurvedBar, CylinderSurface, GraspSurface, PlaneBar
from ..task.trajectory import LinearTrajectory, Trajectory, WaypointTrajectory
from .config import ANGLE_SCALE, LENGTH_SCALE, TIME_SCALE, ArmSpec, ExperimentConfig, PoseSpec

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class Scales:
    """File units to SI: multiply a file number by these."""

    length: float
    angle: float
    time: float


@dataclass
class Experiment:
    """A ready-to-run experiment.

    Attributes
    ----------
    name : str
        Experiment name from the file.
    path : str
        File it was read from.
    task : DualArmTask
        Arms, object, surface and path in SI units.
    initial : DualArmState
        Initial joints and grasp.
    options : StepOptions
        Step-problem settings.
    solver_name : str
        Registry name of the solver.
    solver_options : dict
        Options handed to the solver's factory.
    leader_gain : float
        Leader tracking gain [1/s].
    policy : str
        Infeasible-step policy.
    duration : float
        Run length [s].
    limits : RunLimits
        Tolerances, singularity threshold and duration cap of the run.
    project : bool or None
        Position-level drift correction in the rollout (None: the default for the
        solver, see :func:`~dualarm_qp.control.rollout.rollout`).
    fallback : str or None
        Solver for a feasible step the configured hard-limit solver fails on.
    notes : dict
        Reconstruction facts worth reporting (leader IK branch, follower base, ...).
    """

    name: str
    path: str
    task: DualArmTask
    initial: DualArmState
    options: StepOptions
    solver_name: str
    solver_options: dict[str, Any]
    leader_gain: float
    policy: Policy
    duration: float
    limits: RunLimits = field(default_factory=RunLimits)
    project: bool | None = None
    fallback: str | None = "nullspace"
    notes: dict[str, Any] = field(default_factory=dict)

    def controller(self, *, fallback: bool = True) -> DualArmController:
        """Return a fresh controller with the configured solver.

        ``fallback=False`` leaves out the fallback solver (the bench measures each
        solver's own success).
        """
        solver = get_solver(self.solver_name, **self.solver_options)
        backup = None
        if (fallback and self.fallback is not None and self.fallback != self.solver_name
                and solver_info(self.solver_name).hard_bounds):
            backup = get_solver(self.fallback)
        return DualArmController(self.task, solver, self.options,
                                 leader_gain=self.leader_gain, policy=self.policy,
                                 fallback=backup)


def _pose(spec: PoseSpec, sc: Scales) -> FloatArray:
    if spec.rotation is not None:
        R = np.asarray(spec.rotation, dtype=float)
        # Re-orthonormalise what the file rounded (checked to 1e-6 on load).
        u, _, vt = np.linalg.svd(R)
        R = u @ vt
    elif spec.rpy is not None:
        r, p, y = (v * sc.angle for v in spec.rpy)
        R = rot_z(y) @ rot_y(p) @ rot_x(r)
    else:
        R = np.eye(3)
    return make_pose(R, np.asarray(spec.position, dtype=float) * sc.length)


T = TypeVar("T")


def _required(value: T | None, key: str, path: str | None = None) -> T:
    """``value``, which the schema guarantees; a clear error if it is missing anyway."""
    if value is None:
        raise ConfigError("missing required key", path=path, key=key)
    return value


def _vec(values: list[float] | None, scale: float, n: int, key: str, path: str) -> Any:
    if values is None:
        return None
    if len(values) != n:
        raise ConfigError(f"needs {n} values, got {len(values)}", path=path, key=key)
    arr = np.asarray(values, dtype=float) * scale
    if not np.isfinite(arr).all() and not key.endswith(("q_min", "q_max", "qd_max")):
        raise ConfigError("values must be finite numbers", path=path, key=key)
    if np.isnan(arr).any():
        raise ConfigError("values must not be NaN", path=path, key=key)
    return arr


def _arm(spec: ArmSpec, sc: Scales, role: str, base: FloatArray | None, path: str) -> SerialArm:
    tool = None if spec.tool is None else _pose(spec.tool, sc)
    if spec.preset == "puma560":
        arm = puma560(base=base, tool=tool, name=f"{role} puma560")
        n = 6
        dh = arm.dh
    else:
        dh_spec = _required(spec.dh, f"{role}.dh", path)
        rows = np.asarray(dh_spec.rows, dtype=float)
        scale = np.array([sc.length, sc.angle, sc.length, sc.angle][: rows.shape[1]])
        dh = DHTable.from_rows(rows * scale, dh_spec.convention)
        n = dh.n
        arm = SerialArm(dh, base=base, tool=tool, name=role)
    q_min = _vec(spec.q_min, sc.angle, n, f"{role}.q_min", path)
    q_max = _vec(spec.q_max, sc.angle, n, f"{role}.q_max", path)
    qd_max = _vec(spec.qd_max, sc.angle / sc.time, n, f"{role}.qd_max", path)
    if q_min is None and q_max is None and qd_max is None:
        return arm
    return SerialArm(
        dh,
        q_min=arm.q_min if q_min is None else q_min,
        q_max=arm.q_max if q_max is None else q_max,
        qd_max=arm.qd_max if qd_max is None else qd_max,
        base=arm.base,
        tool=arm.tool,
        name=arm.name,
    )


def _surface(cfg: ExperimentConfig, sc: Scales) -> GraspSurface:
    s = cfg.object.surface
    if s.type == "plane_bar":
        r_min = np.zeros(3) if s.r_min is None else np.asarray(s.r_min, dtype=float) * sc.length
        r_max = (np.array([0.0, 0.0, 0.4]) if s.r_max is None
                 else np.asarray(s.r_max, dtype=float) * sc.length)
        return PlaneBar(r_min=r_min, r_max=r_max)
    radius = _required(s.radius, "object.surface.radius") * sc.length
    lo, hi = (v * sc.length for v in _required(s.grasp_range, "object.surface.grasp_range"))
    if s.type == "cylinder":
        azimuth = 0.0 if s.azimuth is None else s.azimuth * sc.angle
        return CylinderSurface(radius, azimuth=azimuth, sigma_min=lo, sigma_max=hi)
    return CurvedBar(radius, side=s.side or "outer", sigma_min=lo, sigma_max=hi)


def _trajectory(cfg: ExperimentConfig, sc: Scales, duration: float) -> Trajectory:
    tr = cfg.trajectory
    if tr.type == "linear":
        T0 = _pose(_required(tr.start, "trajectory.start"), sc)
        v = np.asarray(_required(tr.velocity, "trajectory.velocity"), dtype=float) * (
            sc.length / sc.time)
        return LinearTrajectory(T0[:3, 3], v, R0=T0[:3, :3], t0=0.0, tf=duration)
    waypoints = _required(tr.waypoints, "trajectory.waypoints")
    times = [w.t * sc.time for w in waypoints]
    poses = [_pose(w.pose, sc) for w in waypoints]
    return WaypointTrajectory(times, poses)


def build_experiment(
    cfg: ExperimentConfig,
    path: str = "<config>",
    *,
    solver: str | None = None,
) -> Experiment:
    """Build the task, initial state and controller settings of an experiment.

    Parameters
    ----------
    cfg : ExperimentConfig
        A validated configuration.
    path : str
        File name, for error messages.
    solver : str, optional
        Override of the configured solver name.

    Raises
    ------
    ConfigError
        Inconsistent values that the schema cannot catch (wrong number of joints,
        an IK branch that does not exist, ...), naming the file and key.
    """
    try:
        return _build(cfg, path, solver)
    except ConfigError as err:
        if err.path is None:
            raise ConfigError(str(err), path=path) from None
        raise
    except DualArmError as err:
        raise ConfigError(str(err), path=path) from None


def _build(cfg: ExperimentConfig, path: str, solver: str | None) -> Experiment:
    if solver is None:  # the file's solver: a wrong name is an error in the file
        try:
            solver_info(cfg.solver.name)
        except SolverNotFoundError as err:
            raise ConfigError(str(err), path=path, key="solver.name") from None
    if cfg.solver.options:  # options the solver refuses are an error in the file
        try:
            get_solver(solver or cfg.solver.name, **cfg.solver.options)
        except SolverNotFoundError:
            pass  # an unavailable --solver override: reported by its own message later
        except DualArmError as err:
            raise ConfigError(str(err), path=path, key="solver.options") from None
    sc = Scales(LENGTH_SCALE[cfg.units.length], ANGLE_SCALE[cfg.units.angle],
                TIME_SCALE[cfg.units.time])
    c = cfg.controller
    dt, duration = c.dt * sc.time, c.duration * sc.time
    notes: dict[str, Any] = {}
    surface = _surface(cfg, sc)
    trajectory = _trajectory(cfg, sc, duration)
    H1 = _pose(cfg.object.H1, sc)
    sigma0 = cfg.object.grasp_initial * sc.length

    if cfg.leader.base == "auto":
        raise ConfigError("'auto' is only supported for the follower's base", path=path,
                          key="leader.base")
    leader = _arm(cfg.leader, sc, "leader", _pose(cfg.leader.base, sc), path)

    # Follower: its base may be recovered from the grasp closure at t0 (the paper's case).
    f_spec = cfg.follower
    follower = _arm(f_spec, sc, "follower", None, path)
    if f_spec.initial.joints is None:
        raise ConfigError("the follower's initial state must be given as 'joints'",
                          path=path, key="follower.initial")
    q_f0 = _vec(f_spec.initial.joints, sc.angle, follower.n, "follower.initial.joints", path)
    if f_spec.base == "auto":
        T_base_tool = follower.fk(q_f0)
        base_f = trajectory.pose(trajectory.t0) @ surface.pose(sigma0) @ np.linalg.inv(
            T_base_tool)
        notes["follower_base_m"] = base_f[:3, 3].tolist()
        notes["follower_base_rotation"] = base_f[:3, :3].round(12).tolist()
    else:
        base_f = _pose(f_spec.base, sc)
    follower = follower.with_base(base_f)

    task = DualArmTask(leader, follower, H1, surface, trajectory)
    q_l0 = _leader_initial(cfg, task, sc, path, notes)
    options = StepOptions(
        dt=dt,
        joint_weights=np.broadcast_to(np.asarray(c.weights.joints, dtype=float),
                                      (follower.n,)).copy(),
        grasp_weight=c.weights.grasp / LENGTH_SCALE[c.weights.grasp_unit or cfg.units.length]**2,
        velocity_limits=c.velocity_limits,
        grasp_speed_max=math.inf if c.grasp_speed_max is None
        else c.grasp_speed_max * sc.length / sc.time,
        correction_gain=None if c.correction_gain is None else c.correction_gain / sc.time,
        recovery_fraction=c.recovery_fraction,
        exact_orientation=c.exact_orientation,
        centre_horizon=None if c.centre_horizon is None else c.centre_horizon * sc.time,
    )
    def tolerance(value: list[float] | None) -> tuple[float, float]:
        return (1e-3, 1e-2) if value is None else (value[0] * sc.length, value[1] * sc.angle)

    limits = RunLimits(
        closure=tolerance(c.closure_tolerance), tracking=tolerance(c.tracking_tolerance),
        singular_value_min=c.singular_value_min, singularity_action=c.singularity_action,
        duration_cap=None if c.duration_cap is None else c.duration_cap * sc.time)
    fallback = None if cfg.solver.fallback == "none" else cfg.solver.fallback
    if fallback is not None:
        try:
            info = solver_info(fallback)
        except SolverNotFoundError as err:
            raise ConfigError(str(err), path=path, key="solver.fallback") from None
        if not (info.hard_bounds and info.available):
            raise ConfigError("the fallback must be an installed solver that keeps hard "
                              "limits (or 'none')", path=path, key="solver.fallback",
                              valid=["nullspace", "none"]) from None
    solver_name = solver or cfg.solver.name
    chosen = _solver_info_or_none(solver_name)
    if c.projection and chosen is not None and chosen.hard_bounds:
        raise ConfigError(f"solver '{solver_name}' keeps hard limits; the position-level "
                          "projection is unbounded and would break them (drift is "
                          "corrected through the step's feedback term)", path=path,
                          key="controller.projection", valid=["false"]) from None
    return Experiment(
        name=cfg.name,
        path=path,
        task=task,
        initial=DualArmState(trajectory.t0, q_l0, q_f0, sigma0),
        options=options,
        solver_name=solver_name,
        solver_options=dict(cfg.solver.options),
        leader_gain=1.0 / dt if c.leader_gain is None else c.leader_gain / sc.time,
        policy=c.policy,
        duration=duration,
        limits=limits,
        project=c.projection,
        fallback=fallback,
        notes=notes,
    )


def _solver_info_or_none(name: str) -> SolverInfo | None:
    """Return the registry entry of ``name``, or None when there is none."""
    try:
        return solver_info(name)
    except SolverNotFoundError:
        return None


def _leader_initial(cfg: ExperimentConfig, task: DualArmTask, sc: Scales, path: str,
                    notes: dict[str, Any]) -> FloatArray:
    spec = cfg.leader.initial
    leader = task.leader
    if spec.joints is not None:
        q = _vec(spec.joints, sc.angle, leader.n, "leader.initial.joints", path)
        return np.asarray(q)
    b = _required(spec.ik_branch, "leader.initial.ik_branch", path)
    if cfg.leader.preset != "puma560":
        raise ConfigError("ik_branch needs the puma560 preset; give 'joints' for a DH arm",
                          path=path, key="leader.initial.ik_branch")
    T = task.leader_target(task.trajectory.t0)
    try:
        sol = ik_branch(leader, T, b.arm, b.elbow, b.wrist)
    except DualArmError as err:
        valid = [f"arm={s.arm} elbow={s.elbow} wrist={s.wrist}" for s in puma560_ik(leader, T)]
        raise ConfigError(f"the leader's IK branch is not valid at D(t0): {err}", path=path,
                          key="leader.initial.ik_branch", valid=valid) from None
    notes["leader_ik_branch"] = {"arm": b.arm, "elbow": b.elbow, "wrist": b.wrist}
    notes["leader_q0_deg"] = np.rad2deg(sol.q).round(6).tolist()
    return np.asarray(sol.q)
