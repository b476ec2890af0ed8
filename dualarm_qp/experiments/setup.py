"""Turn a validated :class:`ExperimentConfig` into library objects, in SI units."""

from __future__ import annotations

import contextlib
import dataclasses
import math
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TypeVar

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from ..control.controller import ControlOutput, DualArmController
from ..control.loads import hand_wrenches
from ..control.rollout import RunLimits
from ..errors import (
    ConfigError,
    DualArmError,
    InvalidInputError,
    PairingError,
    SolverNotFoundError,
)
from ..kinematics.arm import DHTable, SerialArm
from ..kinematics.ik import ik_dls
from ..kinematics.puma560 import puma560
from ..kinematics.puma_ik import ik_branch, puma560_ik
from ..kinematics.robots import EXAMPLE_ROBOTS, RobotModelError, example_robot_arm, urdf_arm
from ..poses import pose
from ..solvers.base import DEFAULT_TOLERANCE, Tolerance
from ..solvers.policy import Policy
from ..solvers.registry import (
    SolverInfo,
    SolverOptionError,
    canonical_name,
    check_pairing,
    get_solver,
    solver_info,
)
from ..step.build import StepBuilder
from ..step.options import StepOptions
from ..step.parts import CostTerm, Limit, Task
from ..step.state import DualArmState
from ..task.contact import GRAVITY_ALONG_PUSH_MIN, SupportContact
from ..task.loads import ObjectLoad, UnbalancedLoadError
from ..task.scene import DualArmTask
from ..task.surfaces import CurvedBar, CylinderSurface, GraspSurface, PlaneBar
from ..task.torques import torque_limits_of
from ..task.trajectory import LinearTrajectory, Trajectory, WaypointTrajectory
from .config import (
    ANGLE_SCALE,
    LENGTH_SCALE,
    MIN_DT_S,
    TIME_SCALE,
    ArmSpec,
    ExperimentConfig,
    InitialSpec,
    PoseSpec,
    SurfaceSpec,
)
from .options import SolverFlagError, SolverOptions, flag_error, options_for
from .setup_checks import check_acceleration_limits, check_physics_tau_max, check_within_reach
from .setup_scene import scene_of

#: A start further than this from its pose at t0 (leader: D(t0) H1^-1; follower: the
#: grasp closure) is an error in the file: [m] and [rad] (1 mm, 0.1 deg), or the run's
#: own tolerance (``closure_tolerance`` / ``tracking_tolerance``) when that is tighter.
START_TOLERANCE = (1e-3, math.radians(0.1))

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
    initial_rates : {"rest", "path"}
        How the run starts: at rest, or moving as the path's first step asks
        (:meth:`start_rates`).
    limits_extra : tuple of Limit
        Limits of the user's added to the step (``limits=`` of the controller).
    tasks_extra : tuple of Task
        Tasks of the user's added to the step (``tasks=`` of the controller).
    costs_extra : tuple of CostTerm
        Cost terms of the user's added to the step (``costs=`` of the controller).
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
    initial_rates: str = "rest"
    limits_extra: tuple[Limit, ...] = ()
    tasks_extra: tuple[Task, ...] = ()
    costs_extra: tuple[CostTerm, ...] = ()

    def controller(
        self,
        *,
        fallback: bool = True,
        tolerance: Tolerance | None = None,
        on_step: Callable[[ControlOutput], None] | None = None,
        acceleration_limits: bool | None = None,
    ) -> DualArmController:
        """Return a fresh controller with the configured solver.

        The one place a controller is built from an experiment (runs, the bench, the
        step-suite generator).

        Parameters
        ----------
        fallback : bool
            False leaves out the fallback solver (the bench measures each solver's own
            success).
        tolerance : Tolerance, optional
            What counts as meeting the equality and the bounds (default
            :data:`~dualarm_qp.solvers.base.DEFAULT_TOLERANCE`).
        on_step : callable, optional
            Called with every step's :class:`~dualarm_qp.control.controller.ControlOutput`
            (see :class:`~dualarm_qp.control.controller.DualArmController`).
        acceleration_limits : bool, optional
            Override the configured ``acceleration_limits`` (:meth:`start_rates` solves
            the first step without them).

        Raises
        ------
        PairingError
            A limit that gives rows with a solver that takes boxes only.
        """
        solver = get_solver(self.solver_name, **self.solver_options)
        backup = None
        if (fallback and self.fallback is not None and self.fallback != self.solver_name
                and solver_info(self.solver_name).hard_bounds):
            backup = get_solver(self.fallback)
        # A step may leave half of the run's tracking and closure tolerances at the next
        # sample (the lookahead slows it otherwise): the other half is the feedback's.
        budget = (0.5 * min(self.limits.tracking[0], self.limits.closure[0]),
                  0.5 * min(self.limits.tracking[1], self.limits.closure[1]))
        options = self.options
        if acceleration_limits is not None:
            options = dataclasses.replace(options, acceleration_limits=acceleration_limits)
        return DualArmController(self.task, solver, options,
                                 leader_gain=self.leader_gain, policy=self.policy,
                                 tolerance=DEFAULT_TOLERANCE if tolerance is None else tolerance,
                                 fallback=backup, on_step=on_step, error_budget=budget,
                                 singularity_escape=self.limits.singular_value_min or 1e-3,
                                 limits=self.limits_extra, tasks=self.tasks_extra,
                                 costs=self.costs_extra)

    def start_rates(self) -> FloatArray | None:
        """Return the rates the run starts with [rad/s, m/s] (decision order), or None.

        With ``initial_rates: path`` the pair is taken to move already as the path's
        first step asks: that step's answer without acceleration limits.
        """
        if self.initial_rates == "rest":
            return None
        free = self.controller(acceleration_limits=False)
        out = free.step(self.initial)
        if not out.applied:
            return None
        return free.layout.join(out.ql_dot, out.qf_dot, out.m, out.m_leader)


def _pose(spec: PoseSpec, sc: Scales) -> FloatArray:
    """Return the file's pose in SI, read by :func:`~dualarm_qp.poses.pose` as in Python."""
    return pose(np.asarray(spec.position, dtype=float) * sc.length,
                rpy=None if spec.rpy is None else np.asarray(spec.rpy, dtype=float) * sc.angle,
                rotation=spec.rotation)


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
    if not np.isfinite(arr).all() and not key.endswith(("q_min", "q_max", "qd_max",
                                                        "qdd_max", "tau_max")):
        raise ConfigError("values must be finite numbers", path=path, key=key)
    if np.isnan(arr).any():
        raise ConfigError("values must not be NaN", path=path, key=key)
    return arr


@contextlib.contextmanager
def _at(key: str, path: str) -> Iterator[None]:
    """Report a library refusal inside the block as a ConfigError naming ``key``."""
    try:
        yield
    except ConfigError:
        raise
    except DualArmError as err:
        raise ConfigError(str(err), path=path, key=key) from None


def _arm(spec: ArmSpec, sc: Scales, role: str, base: FloatArray | None, path: str) -> SerialArm:
    tool = None if spec.tool is None else _pose(spec.tool, sc)
    if spec.preset == "puma560":
        arm = puma560(base=base, tool=tool, name=f"{role} puma560")
    elif spec.dh is not None:
        rows = np.asarray(spec.dh.rows, dtype=float)
        scale = np.array([sc.length, sc.angle, sc.length, sc.angle][: rows.shape[1]])
        arm = SerialArm(DHTable.from_rows(rows * scale, spec.dh.convention), base=base,
                        tool=tool, name=role)
    else:
        arm = _robot_arm(spec, role, base, tool, path)
    n = arm.n
    q_min = _vec(spec.q_min, sc.angle, n, f"{role}.q_min", path)
    q_max = _vec(spec.q_max, sc.angle, n, f"{role}.q_max", path)
    qd_max = _vec(spec.qd_max, sc.angle / sc.time, n, f"{role}.qd_max", path)
    qdd_max = _vec(spec.qdd_max, sc.angle / sc.time**2, n, f"{role}.qdd_max", path)
    if q_min is None and q_max is None and qd_max is None and qdd_max is None:
        return arm
    lo = arm.q_min if q_min is None else q_min
    hi = arm.q_max if q_max is None else q_max
    for key, values, wrong in (("q_min", q_min, np.inf), ("q_max", q_max, -np.inf)):
        if values is not None and (values == wrong).any():
            i = int(np.flatnonzero(values == wrong)[0])
            raise ConfigError(f"joint {i + 1}: {key} is {wrong:+g}, which no joint can reach "
                              f"(an open side is {-wrong:+g})", path=path,
                              key=f"{role}.{key}")
    crossed = np.flatnonzero(lo > hi)
    if crossed.size:
        i = int(crossed[0])
        raise ConfigError(f"joint {i + 1}: q_min ({lo[i] / sc.angle:g}) is above q_max "
                          f"({hi[i] / sc.angle:g})", path=path,
                          key=f"{role}.q_min" if q_min is not None else f"{role}.q_max")
    for key, values, unit in (("qd_max", qd_max, sc.angle / sc.time),
                              ("qdd_max", qdd_max, sc.angle / sc.time**2)):
        if values is not None and not (values > 0).all():
            i = int(np.flatnonzero(~(values > 0))[0])
            what = "a speed" if key == "qd_max" else "an acceleration"
            raise ConfigError(f"joint {i + 1}: {what} limit must be > 0, got "
                              f"{values[i] / unit:g}", path=path, key=f"{role}.{key}")
    return arm.with_limits(q_min, q_max, qd_max, qdd_max)


def _tau_max(spec: ArmSpec, arm: SerialArm, role: str, on: bool, path: str
             ) -> FloatArray | None:
    """Return the arm's ``tau_max`` [N m] as given (checked), or None for the default.

    With ``controller.torque_limits`` on, an arm without ``tau_max`` must have a URDF
    ``effort`` (the default); a DH arm or preset has none.
    """
    key = f"{role}.tau_max"
    given = _vec(spec.tau_max, 1.0, arm.n, key, path)
    if given is not None:
        bad = np.flatnonzero(~(given > 0.0))
        if bad.size:
            j = int(bad[0])
            raise ConfigError(f"joint {j + 1}: a torque limit must be > 0 N m (.inf: no "
                              f"limit), got {given[j]:g}", path=path, key=key)
    if on:
        with _at(key, path):
            torque_limits_of(arm, given, role)
    return given


def _robot_arm(spec: ArmSpec, role: str, base: FloatArray | None, tool: FloatArray | None,
               path: str) -> SerialArm:
    """One chain of a URDF (``urdf``) or of an example-robot-data robot (``example_robot``).

    Joint ranges and speed limits are the URDF's; the file's ``q_min`` / ``q_max`` /
    ``qd_max`` override them (see :func:`_arm`).
    """
    try:
        if spec.urdf is not None:
            key = f"{role}.urdf"
            file = Path(spec.urdf.file)
            if not file.is_absolute():  # relative to the experiment file's folder
                file = Path(path).parent / file
            return urdf_arm(file, spec.urdf.root, spec.urdf.tip, base=base, tool=tool,
                            name=f"{role} {file.stem}")
        robot = _required(spec.example_robot, f"{role}.example_robot", path)
        key = f"{role}.example_robot"
        return example_robot_arm(robot.name, robot.root, robot.tip, base=base, tool=tool,
                                 name=f"{role} {robot.name}")
    except RobotModelError as err:
        field = err.field if err.field in ("file", "name", "root", "tip") else None
        known = err.field == "name" and "unknown robot" in str(err)
        raise ConfigError(str(err), path=path, key=f"{key}.{field}" if field else key,
                          valid=sorted(EXAMPLE_ROBOTS) if known else ()) from None


def _model_key(spec: ArmSpec, role: str) -> str:
    """Return the key of ``role``'s arm model, for messages (``leader.dh.rows``, ...)."""
    key = spec.model_key
    return f"{role}.{key}.rows" if key == "dh" else f"{role}.{key}"


def _surface(s: SurfaceSpec, sc: Scales, key: str) -> GraspSurface:
    if s.type == "plane_bar":
        r_min = np.zeros(3) if s.r_min is None else np.asarray(s.r_min, dtype=float) * sc.length
        r_max = (np.array([0.0, 0.0, 0.4]) if s.r_max is None
                 else np.asarray(s.r_max, dtype=float) * sc.length)
        return PlaneBar(r_min=r_min, r_max=r_max)
    radius = _required(s.radius, f"{key}.radius") * sc.length
    lo, hi = (v * sc.length for v in _required(s.grasp_range, f"{key}.grasp_range"))
    if s.type == "cylinder":
        azimuth = 0.0 if s.azimuth is None else s.azimuth * sc.angle
        return CylinderSurface(radius, azimuth=azimuth, sigma_min=lo, sigma_max=hi)
    return CurvedBar(radius, side=s.side or "outer", sigma_min=lo, sigma_max=hi)


#: Gravity when the file gives none: world z up [m/s^2].
STANDARD_GRAVITY = (0.0, 0.0, -9.81)


def _load(cfg: ExperimentConfig, sc: Scales, path: str) -> ObjectLoad:
    """Return the object's load in SI (``object.mass`` must be given)."""
    o = cfg.object
    mass = _required(o.mass, "object.mass", path)
    centre = np.zeros(3) if o.mass_centre is None else np.asarray(o.mass_centre) * sc.length
    gravity = (np.asarray(STANDARD_GRAVITY) if o.gravity is None
               else np.asarray(o.gravity, dtype=float) * sc.length / sc.time**2)
    with _at("object.mass", path):
        return ObjectLoad(mass, centre, gravity)


def _check_load(task: DualArmTask, q_l0: FloatArray, sigma0: float, sigma_l0: float,
                path: str) -> None:
    """Refuse a load the grasps cannot hold at the start, naming the key to change.

    ``object.gravity`` when the force cannot be balanced (gravity along a direction no
    grasp carries), ``object.mass_centre`` when only its moment cannot (the mass centre
    off an axis both grasps turn about).
    """
    if task.load is None or task.contact is not None:  # a support is checked by _support
        return
    try:
        hand_wrenches(task, q_l0, sigma0, sigma_l0)
    except UnbalancedLoadError as err:
        T_obj = task.object_pose(q_l0, sigma_l0)
        centre = T_obj[:3, :3].T @ (task.leader.fk(q_l0)[:3, 3] - T_obj[:3, 3])
        at_grasp = dataclasses.replace(task.load, mass_centre=centre)
        try:
            hand_wrenches(dataclasses.replace(task, load=at_grasp), q_l0, sigma0, sigma_l0)
            key = "object.mass_centre"
        except UnbalancedLoadError:
            key = "object.gravity"
        raise ConfigError(f"at the start {err}", path=path, key=key) from None


def _support(cfg: ExperimentConfig, sc: Scales, plane: GraspSurface, H1: FloatArray,
             trajectory: Trajectory, sigma0: float, path: str, notes: dict[str, Any]
             ) -> tuple[SupportContact, GraspSurface]:
    """Return the Case 2 contact and its support line at t0 (the follower's first path).

    Errors name the key to change: ``object.gravity`` when gravity has no component
    along the push at the start, ``object.mass_centre`` when no point of the box holds
    the object with a push, ``object.grasp_initial`` when the start needs a pull.
    """
    load = _load(cfg, sc, path)
    mass, centre, gravity = load.mass, load.mass_centre, load.gravity
    if not isinstance(plane, PlaneBar):  # the schema allows only a plane_bar
        raise ConfigError("a support needs a plane_bar surface", path=path,
                          key="object.surface.type")
    with _at("object", path):
        contact = SupportContact(mass=mass, mass_centre=centre, gravity=gravity, plane=plane,
                                 H1=H1)
    R0 = trajectory.pose(trajectory.t0)[:3, :3]
    g0 = contact.gravity_in_object(R0)
    if abs(float(g0[0])) <= GRAVITY_ALONG_PUSH_MIN * float(np.linalg.norm(g0)):
        raise ConfigError(
            f"at the start gravity in object coordinates is {np.round(g0, 6).tolist()} m/s^2: "
            "it has no component along the object's x axis (the supporting face's normal), "
            "so the follower's push carries none of the weight; turn the object or gravity",
            path=path, key="object.gravity")
    try:
        line = contact.line(R0)
    except DualArmError as err:
        raise ConfigError(
            "no support at the start: the follower pushes on the support line from the "
            "leader's hand through the mass centre (both projected on the face), on the "
            "side where the push h is > 0, and that part must lie in the box of "
            f"object.surface (r_min, r_max); here: {err}", path=path,
            key="object.mass_centre") from None
    with _at("object.grasp_initial", path):
        h0 = contact.force(line, sigma0)
    notes["support"] = {
        "mass_kg": mass, "mass_centre_m": centre.tolist(), "gravity_world_m_s2":
        gravity.tolist(), "gravity_object_t0_m_s2": g0.tolist(),
        "line_origin_m": line.origin.tolist(), "line_direction": line.tangent(0.0).tolist(),
        "grasp_range_m": [line.sigma_min, line.sigma_max], "force_t0_N": h0}
    return contact, line


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
    solver_options: SolverOptions | None = None,
    limits: Sequence[Limit] = (),
    tasks: Sequence[Task] = (),
    costs: Sequence[CostTerm] = (),
    dt: float | None = None,
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
    solver_options : mapping, optional
        Options per solver name from the command line
        (:func:`~dualarm_qp.experiments.options.parse_solver_options`); those of the
        solver that runs are applied over the file's.
    limits : sequence of Limit
        Limits of the user's added to the step (:mod:`dualarm_qp.step.parts`), checked
        against the solver here (a limit that gives rows needs a solver that takes
        rows).
    tasks : sequence of Task
        Tasks of the user's added to the step: equality rows, or with a ``weight`` a
        term of the cost (``examples/custom_task.py``).
    costs : sequence of CostTerm
        Cost terms of the user's, summed with the paper's centring.
    dt : float, optional
        Sampling interval [s] instead of the file's ``controller.dt`` (e.g. 1e-3 for a
        1 kHz loop). The gains and the range-centring horizon the file leaves to their
        default (``1/dt``, ``dt``) follow it.

    Notes
    -----
    The file's ``solver.options`` belong to the file's solver: they are checked against
    it (when it is installed) and handed to the solver only when the solver that runs
    is that one (``solver`` None or the same name); another solver runs with its
    defaults and its own command-line options.

    Raises
    ------
    ConfigError
        Inconsistent values that the schema cannot catch (wrong number of joints,
        an IK branch that does not exist, a follower base that does not close the grasp,
        an option the file's solver refuses, ...), naming the file and key.
    InvalidInputError
        A command-line option the running solver refuses, naming ``--solver-option``;
        a ``dt`` that is not a finite number of at least 1e-6 s.
    PairingError
        A limit that gives rows (of ``limits`` or of the file) with a solver that takes
        boxes only: the message names the file (and the key ``solver.name`` when the
        file chose the solver), the solver, the limit and the solvers that can.
    """
    if dt is not None and not (math.isfinite(dt) and dt >= MIN_DT_S):
        raise InvalidInputError(f"dt must be a sampling interval of at least {MIN_DT_S:g} s, "
                                f"got {dt!r}")
    try:
        exp = _build(cfg, path, solver, solver_options, dt)
        exp.limits_extra, exp.tasks_extra, exp.costs_extra = (
            tuple(limits), tuple(tasks), tuple(costs))
        builder = StepBuilder(exp.task, exp.options, limits=exp.limits_extra,
                              tasks=exp.tasks_extra, costs=exp.costs_extra)
        check_pairing(solver_info(exp.solver_name), builder.row_limits, builder.full_cost)
        return exp
    except ConfigError as err:
        if err.path is None:
            raise ConfigError(str(err), path=path) from None
        raise
    except PairingError as err:
        where = f"{path}: key 'solver.name': " if solver is None else f"{path}: "
        raise PairingError(f"{where}{err}", solver=err.solver, limits=err.limits,
                           able=err.able) from None
    except SolverFlagError:
        raise
    except DualArmError as err:
        raise ConfigError(str(err), path=path) from None


def _solver_options(cfg: ExperimentConfig, path: str, solver: str | None,
                    cli: SolverOptions | None) -> dict[str, Any]:
    """Return the options the running solver gets (see :func:`build_experiment`), checked."""
    own = cfg.solver.options
    file_info = None
    try:
        file_info = solver_info(cfg.solver.name)
    except SolverNotFoundError as err:
        if solver is None:  # the file's solver runs: a wrong name is an error in the file
            raise ConfigError(str(err), path=path, key="solver.name") from None
    if own and file_info is not None:  # options the file's solver refuses: the file's fault
        try:
            get_solver(cfg.solver.name, **own)
        except SolverOptionError as err:
            raise ConfigError(err.reason, path=path, key=f"solver.options.{err.option}",
                              valid=err.valid) from None
        except DualArmError as err:
            raise ConfigError(str(err), path=path, key="solver.options") from None
    running = solver or cfg.solver.name
    same = canonical_name(running) == canonical_name(cfg.solver.name)
    extra = options_for(running, cli)
    chosen = {**(own if same else {}), **extra}
    if extra:
        try:
            solver_info(running)
        except SolverNotFoundError:
            return chosen  # reported by its own message when the solver is built
        try:
            get_solver(running, **chosen)
        except SolverOptionError as err:
            if err.option in extra:
                raise flag_error(err) from None
            raise ConfigError(err.reason, path=path, key=f"solver.options.{err.option}",
                              valid=err.valid) from None
        except DualArmError as err:
            raise SolverFlagError(f"--solver-option for '{running}': {err}") from None
    return chosen


def _build(cfg: ExperimentConfig, path: str, solver: str | None,
           cli_options: SolverOptions | None, dt_s: float | None = None) -> Experiment:
    solver_options = _solver_options(cfg, path, solver, cli_options)
    sc = Scales(LENGTH_SCALE[cfg.units.length], ANGLE_SCALE[cfg.units.angle],
                TIME_SCALE[cfg.units.time])
    c = cfg.controller
    dt, duration = c.dt * sc.time if dt_s is None else float(dt_s), c.duration * sc.time
    if dt < MIN_DT_S:
        raise ConfigError(f"dt is {dt:.3g} s; the shortest sampling interval is "
                          f"{MIN_DT_S:g} s", path=path, key="controller.dt")
    notes: dict[str, Any] = {}
    with _at("object.surface", path):
        surface = _surface(cfg.object.surface, sc, "object.surface")
    with _at("trajectory", path):
        trajectory = _trajectory(cfg, sc, duration)
    with _at("object.H1", path):
        H1 = np.eye(4) if cfg.object.H1 is None else _pose(cfg.object.H1, sc)
    sigma0 = cfg.object.grasp_initial * sc.length
    contact: SupportContact | None = None
    if cfg.object.contact == "support":
        contact, surface = _support(cfg, sc, surface, H1, trajectory, sigma0, path, notes)
    with _at("object.grasp_initial", path):
        surface.pose(sigma0)
    leader_surface: GraspSurface | None = None
    sigma_l0 = 0.0
    if cfg.object.leader_surface is not None and cfg.object.leader_grasp_initial is not None:
        with _at("object.leader_surface", path):
            leader_surface = _surface(cfg.object.leader_surface, sc, "object.leader_surface")
        sigma_l0 = cfg.object.leader_grasp_initial * sc.length
        with _at("object.leader_grasp_initial", path):
            leader_surface.pose(sigma_l0)

    def tolerance(value: list[float] | None) -> tuple[float, float]:
        return (1e-3, 1e-2) if value is None else (value[0] * sc.length, value[1] * sc.angle)

    with _at("controller", path):
        limits = RunLimits(
            closure=tolerance(c.closure_tolerance), tracking=tolerance(c.tracking_tolerance),
            singular_value_min=c.singular_value_min, singularity_action=c.singularity_action,
            duration_cap=None if c.duration_cap is None else c.duration_cap * sc.time)

    if cfg.leader.base == "auto":
        raise ConfigError("'auto' is only supported for the follower's base", path=path,
                          key="leader.base")
    with _at("leader", path):
        leader = _arm(cfg.leader, sc, "leader", _pose(cfg.leader.base, sc), path)
    with _at("follower", path):
        follower = _arm(cfg.follower, sc, "follower", None, path)
    for role, arm, least in (("leader", leader, 6), ("follower", follower, 5)):
        if arm.n < least:
            raise ConfigError(f"the {role} has {arm.n} joints; it needs at least {least} "
                              "to carry the object along a 6-DoF path", path=path,
                              key=_model_key(getattr(cfg, role), role))
    check_acceleration_limits(cfg, {"leader": leader, "follower": follower}, path)
    check_physics_tau_max(cfg, {"leader": leader, "follower": follower}, path)

    # Follower: its base may be recovered from the grasp closure at t0 (the paper's case).
    f_spec = cfg.follower
    q_f0: FloatArray | None = None
    if f_spec.base == "auto":
        if f_spec.initial.joints is None:
            form = "ik_branch" if f_spec.initial.ik_branch is not None else "near"
            raise ConfigError(f"with 'base: auto' the base is recovered from the initial "
                              f"joints, so a pose to solve ({form}) is ambiguous: give "
                              "'joints', or give the follower's base explicitly",
                              path=path, key=f"follower.initial.{form}",
                              valid=["joints"])
        q_f0 = _vec(f_spec.initial.joints, sc.angle, follower.n, "follower.initial.joints",
                    path)
        with _at("follower.initial.joints", path):
            T_base_tool = follower.fk(q_f0)
            base_f = trajectory.pose(trajectory.t0) @ surface.pose(sigma0) @ np.linalg.inv(
                T_base_tool)
        notes["follower_base_m"] = base_f[:3, 3].tolist()
        notes["follower_base_rotation"] = base_f[:3, :3].round(12).tolist()
    else:
        with _at("follower.base", path):
            base_f = _pose(f_spec.base, sc)
    with _at("follower", path):
        follower = follower.with_base(base_f)
        task = DualArmTask(leader, follower, H1, surface, trajectory,
                           leader_surface=leader_surface, contact=contact,
                           load=None if cfg.object.mass is None else _load(cfg, sc, path))
    check_within_reach(cfg, task.leader, "leader", _path_targets(cfg, task, sigma_l0, path),
                       path)
    q_l0 = _leader_initial(cfg, task, sc, path, notes, limits.tracking, sigma_l0)
    if q_f0 is None:
        q_f0 = _follower_initial(cfg, task, sc, path, notes, q_l0, sigma0, limits.closure,
                                 sigma_l0)
    _check_load(task, q_l0, sigma0, sigma_l0, path)
    scene = scene_of(cfg, sc.length, sc.angle, sc.time, task.leader, task.follower,
                     (q_l0, q_f0, task.leader.fk(q_l0) @ task.H1_at(sigma_l0)), dt, path)
    if scene is not None:
        task = dataclasses.replace(task, scene=scene)

    tau_max = {role: _tau_max(getattr(cfg, role), arm, role, c.torque_limits, path)
               for role, arm in (("leader", task.leader), ("follower", task.follower))}

    weights = np.asarray(c.weights.joints, dtype=float)
    if weights.size not in (1, follower.n):
        raise ConfigError(f"needs one weight or {follower.n} (one per follower joint), got "
                          f"{weights.size}", path=path, key="controller.weights.joints")
    leader_weights = np.asarray(c.weights.leader_joints, dtype=float)
    if leader_weights.size not in (1, leader.n):
        raise ConfigError(f"needs one weight or {leader.n} (one per leader joint), got "
                          f"{leader_weights.size}", path=path,
                          key="controller.weights.leader_joints")
    with _at("controller", path):
        options = StepOptions(
            dt=dt,
            joint_weights=np.broadcast_to(weights, (follower.n,)).copy(),
            leader_joint_weights=np.broadcast_to(leader_weights, (leader.n,)).copy(),
            grasp_weight=c.weights.grasp / LENGTH_SCALE[c.weights.grasp_unit
                                                        or cfg.units.length]**2,
            velocity_limits=c.velocity_limits,
            grasp_speed_max=math.inf if c.grasp_speed_max is None
            else c.grasp_speed_max * sc.length / sc.time,
            acceleration_limits=c.acceleration_limits,
            torque_limits=c.torque_limits,
            torque_approach=None if c.torque_approach is None else c.torque_approach * sc.time,
            leader_tau_max=tau_max["leader"],
            follower_tau_max=tau_max["follower"],
            grasp_acc_max=math.inf if c.grasp_acc_max is None
            else c.grasp_acc_max * sc.length / sc.time**2,
            correction_gain=None if c.correction_gain is None else c.correction_gain / sc.time,
            leader_gain=None if c.leader_gain is None else c.leader_gain / sc.time,
            recovery_fraction=c.recovery_fraction,
            exact_orientation=c.exact_orientation,
            centre_horizon=None if c.centre_horizon is None else c.centre_horizon * sc.time,
        )
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
        initial=DualArmState(trajectory.t0, q_l0, q_f0, sigma0, sigma_l0),
        options=options,
        solver_name=solver_name,
        solver_options=solver_options,
        leader_gain=float(options.leader_gain or 0.0),
        policy=c.policy,
        duration=duration,
        limits=limits,
        project=c.projection,
        fallback=fallback,
        notes=notes,
        initial_rates=c.initial_rates,
    )


def _solver_info_or_none(name: str) -> SolverInfo | None:
    """Return the registry entry of ``name``, or None when there is none."""
    try:
        return solver_info(name)
    except SolverNotFoundError:
        return None


def _pose_gap(T_a: FloatArray, T_b: FloatArray) -> tuple[float, float]:
    """Distance [m] and angle [rad] between two poses."""
    dp = float(np.linalg.norm(T_a[:3, 3] - T_b[:3, 3]))
    dw = float(np.linalg.norm(pin.log3(T_a[:3, :3] @ T_b[:3, :3].T)))
    return dp, dw


def _start_limit(run_tolerance: tuple[float, float]) -> tuple[float, float]:
    """:data:`START_TOLERANCE`, or the run's tolerance where that is tighter."""
    return (min(START_TOLERANCE[0], run_tolerance[0]),
            min(START_TOLERANCE[1], run_tolerance[1]))


def _gap_text(dp: float, dw: float, limit: tuple[float, float]) -> str:
    return (f"{dp * 1e3:.3f} mm and {math.degrees(dw):.3f} deg (allowed: "
            f"{limit[0] * 1e3:g} mm, {math.degrees(limit[1]):g} deg)")


def _solve_initial(spec: InitialSpec, arm: SerialArm, preset: str | None, T: FloatArray,
                   sc: Scales, role: str, what: str, path: str,
                   notes: dict[str, Any]) -> FloatArray:
    """Joints reaching ``T`` by the IK branch or from the ``near`` joints of ``spec``."""
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
        seed = _vec(_required(spec.near, key, path), sc.angle, arm.n, key, path)
        with _at(key, path):
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


def _path_targets(cfg: ExperimentConfig, task: DualArmTask, sigma_l0: float, path: str
                  ) -> list[tuple[str, FloatArray]]:
    """Return the leader's targets ``D(t) H1^-1`` at the path's ends or waypoints, named."""
    trajectory = task.trajectory
    hand = "object.H1" if task.leader_surface is None else "object.leader_grasp_initial"
    if cfg.trajectory.type == "linear":
        named = [(trajectory.t0, f"D(t0) H1^-1 at the path's start (trajectory.start, {hand})"),
                 (trajectory.tf, "D(t) H1^-1 at the path's end (trajectory.start, "
                                 f"trajectory.velocity, {hand})")]
    else:
        times = (trajectory.times.tolist() if isinstance(trajectory, WaypointTrajectory)
                 else [trajectory.t0, trajectory.tf])
        named = [(float(t), f"D(t) H1^-1 at t = {t:g} s (trajectory.waypoints.{i}.pose, "
                            f"{hand})") for i, t in enumerate(times)]
    with _at("trajectory", path):
        return [(what, task.leader_target(t, sigma_l0)) for t, what in named]


def _leader_initial(cfg: ExperimentConfig, task: DualArmTask, sc: Scales, path: str,
                    notes: dict[str, Any], tracking: tuple[float, float],
                    sigma_l0: float) -> FloatArray:
    spec = cfg.leader.initial
    leader = task.leader
    with _at("trajectory", path):
        T = task.leader_target(task.trajectory.t0, sigma_l0)
    if spec.joints is None:
        return _solve_initial(spec, leader, cfg.leader.preset, T, sc, "leader",
                              "D(t0) H1^-1", path, notes)
    q = np.asarray(_vec(spec.joints, sc.angle, leader.n, "leader.initial.joints", path))
    with _at("leader.initial.joints", path):
        dp, dw = _pose_gap(leader.fk(q), T)
    limit = _start_limit(tracking)
    if not (dp <= limit[0] and dw <= limit[1]):
        raise ConfigError("these joints put the object away from the start of the path "
                          f"D(t0): the leader's tool is off by {_gap_text(dp, dw, limit)}; "
                          "give joints at D(t0) H1^-1, or use 'ik_branch' or 'near'",
                          path=path, key="leader.initial.joints")
    return q


def _follower_initial(cfg: ExperimentConfig, task: DualArmTask, sc: Scales, path: str,
                      notes: dict[str, Any], q_l0: FloatArray, sigma0: float,
                      closure: tuple[float, float], sigma_l0: float) -> FloatArray:
    """Return the follower's joints with an explicit base: given (and checked) or solved."""
    spec = cfg.follower.initial
    follower = task.follower
    with _at("object.grasp_initial", path):
        T = task.follower_target(q_l0, sigma0, sigma_l0)
    check_within_reach(cfg, follower, "follower", [
        ("D(t0) H2(grasp_initial) (object.grasp_initial, object.surface, follower.base)", T)],
        path)
    if spec.joints is None:
        return _solve_initial(spec, follower, cfg.follower.preset, T, sc, "follower",
                              "the grasp D(t0) H2(grasp_initial)", path, notes)
    q = np.asarray(_vec(spec.joints, sc.angle, follower.n, "follower.initial.joints", path))
    with _at("follower.initial.joints", path):
        dp, dw = _pose_gap(follower.fk(q), T)
    limit = _start_limit(closure)
    if not (dp <= limit[0] and dw <= limit[1]):
        raise ConfigError("the base and the initial joints do not close the grasp at t0: "
                          "the follower's tool is off the grasp pose D(t0) H2(grasp_initial) "
                          f"by {_gap_text(dp, dw, limit)}; fix the base or the joints, use "
                          "'base: auto', or solve the joints with 'ik_branch' or 'near'",
                          path=path, key="follower.base")
    return q
