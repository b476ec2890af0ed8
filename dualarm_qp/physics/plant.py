"""The task in MuJoCo as a plant: joint servos at 1 ms substeps, and what it measures.

:class:`MujocoPlant` compiles the model of :func:`~dualarm_qp.physics.mjcf.build_mjcf`,
puts it at the run's start and then, for each controller sample of ``dt``:

* drives every arm joint with a **servo** for ``n = ceil(dt / 1 ms)`` substeps of ``dt /
  n``: a ``position`` servo is ``kp (q_ref - q) + kv (qd_ref - qd)`` with ``q_ref`` the
  commanded rates integrated, and pulled towards the measured joints with the time
  constant ``reference_time`` (``reference: measured``) or not (``integrated``); ``qd_ref``
  is the rates (feed-forward, ramped over the sample from the previous command, so
  that a new command steps no torque); a
  ``velocity`` servo is ``kv (qd_ref - qd)`` only. Both add two feed-forward torques:
  the arm's own gravity and Coriolis torques (MuJoCo's bias forces of the arm joints),
  and the torques that hold the hand's quasi-static share of the load (the minimum-norm
  split of :mod:`dualarm_qp.control.loads`, at the sample's measured state), so that
  what the servo corrects is the dynamics and what the split does not foresee;
* measures, at the end of each sample, the joints, each sliding grasp's coordinate (its
  chain joint) and its slip (off the coordinate at the sample's start plus ``dt`` times
  the commanded sliding speed, with or without ``delay``), the object's pose, each
  hand's wrench on the object from its force/torque sensor, their internal part and
  the follower's share of the load against the plan's split (:mod:`.readout`), the
  joint torques (their peak share of the limits over the substeps), the welds' errors
  and a support's gap, into :attr:`MujocoPlant.log`, and each arm joint's velocity
  error at every substep into :attr:`MujocoPlant.velocity_error`;
* hands the controller the measured state, or with ``delay`` ``d`` the one measured
  ``d`` samples earlier (brought forward by the commands applied since, with
  ``predict``: :mod:`dualarm_qp.control.predict`), and keeps the sensors' reading of
  that state in :attr:`MujocoPlant.readings`.

Contacts (:attr:`PhysicsSettings.contacts
<dualarm_qp.physics.settings.PhysicsSettings.contacts>`): by default the links and the
object touch the obstacles only; with ``all`` they also touch each other, except the
object and the last :data:`~dualarm_qp.physics.mjcf.WRIST_BODIES` bodies of each arm (the
grasping wrists). Pairs that overlap at the start are left out (listed in
:attr:`MujocoPlant.notes`).
"""

from __future__ import annotations

import dataclasses
import math
from collections import deque
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from ..control.measured import HandReading
from ..control.predict import CommandHistory
from ..errors import DualArmError, InvalidInputError
from ..step.state import Command, DualArmState
from ..task.loads import ObjectLoad
from ..task.scene import DualArmTask
from .compliance import WrenchMeasurement
from .gains import ServoGains, servo_gains, set_gains, unstable_gains_advice
from .limits import torque_limits
from .mjcf import PhysicsModel, build_mjcf
from .readout import Readout
from .settings import SUBSTEP, PhysicsSettings
from .statics import against_plan, load_feedforward, simulated_task

FloatArray = NDArray[np.float64]

#: The columns of :attr:`MujocoPlant.log` (one row per controller sample), with units.
LOG_COLUMNS = {
    "t": "s", "tau": "s", "deviation_pos": "m", "deviation_rot": "rad",
    "internal": "N", "support": "N", "slip": "m",
    "weld_leader": "m", "weld_follower": "m", "gap": "m", "torque_ratio_peak": "1",
    "share": "1", "share_plan": "1", "split_error": "1",
}


#: How long the start is held before the first sample [s] (:meth:`MujocoPlant.reset`).
SETTLE = 0.5


#: A weld's position error beyond which the simulation is taken to have diverged [m]:
#: a sound run keeps its welds within a millimetre or so; a few centimetres means the
#: hands have come off the object (:meth:`MujocoPlant.check_stable`).
WELD_ERROR_DIVERGED = 0.05

#: A joint speed beyond which the simulation is taken to have diverged [rad/s, m/s].
SPEED_DIVERGED = 1e4


class PhysicsError(DualArmError):
    """The simulation cannot be built or diverged (NaN or unbounded state)."""


class DivergedError(PhysicsError):
    """The simulation blew up (the servo gains are unstable for the model and substep)."""


def _mujoco() -> Any:
    try:
        import mujoco
    except ImportError:
        raise PhysicsError('the physics check needs MuJoCo: pip install "dualarm-qp[physics]"'
                           ) from None
    return mujoco


class MujocoPlant:
    """The task in MuJoCo, driven by joint servos (see the module docstring).

    Parameters
    ----------
    task : DualArmTask
        The task (arms, object, grasps, scene).
    settings : PhysicsSettings
        Servo gains, delay, default object.
    delay : bool, optional
        Override ``settings.delay``.
    arm_tau_max : dict of str to ndarray, optional
        Each arm's configured ``tau_max`` [N m] (:func:`torque_limits`).
    measurement : WrenchMeasurement, optional
        Updated with the reading of each state handed to the controller (a compliant
        follower's, :mod:`dualarm_qp.physics.compliance`).

    Attributes
    ----------
    delay : int
        Samples the measurement handed to the controller is late (0: the latest).
    readings : list of HandReading
        What the sensors measured with each state handed to the controller (the
        reset's first, then one per :meth:`advance`; as late as the state).
    """

    def __init__(self, task: DualArmTask, settings: PhysicsSettings, *,
                 delay: int | None = None,
                 arm_tau_max: dict[str, FloatArray | None] | None = None,
                 measurement: WrenchMeasurement | None = None) -> None:
        self.task = task
        self.settings = settings
        self.delay = settings.delay if delay is None else int(delay)
        if self.delay < 0:
            raise InvalidInputError(f"delay must be a whole number of samples >= 0, got "
                                    f"{self.delay}")
        #: What MuJoCo simulates: the task, its follower's base moved by
        #: ``settings.base_error`` (the controller keeps the model's).
        self.world = simulated_task(task, settings.base_error)
        self.physics: PhysicsModel = build_mjcf(self.world, settings)
        self.notes: list[str] = list(self.physics.notes)
        self.limits = torque_limits(task, settings, arm_tau_max)
        self._mj = _mujoco()
        pm = self.physics
        #: The object's mass, mass centre and gravity as simulated (the file's, else
        #: ``physics.object_mass`` at the middle of its shape).
        self.load = task.load if task.load is not None else ObjectLoad(
            pm.mass, pm.mass_centre, pm.gravity)
        self._load_task = dataclasses.replace(task, load=self.load)
        self._ff = np.zeros(task.leader.n + task.follower.n)
        self.log: dict[str, list[Any]] = {}
        self.substeps = 1
        #: Each arm joint's servo gains (set by :meth:`reset`, :mod:`.gains`).
        self.gains: ServoGains | None = None
        self.readings: list[HandReading] = []
        self.measurement = measurement
        self._history: deque[tuple[DualArmState, HandReading]] = deque()
        self._commands = CommandHistory(self.delay)

    # -- building ---------------------------------------------------------------------
    def _compile(self, xml: str) -> None:
        mj = self._mj
        try:
            self.model = mj.MjModel.from_xml_string(xml)
        except ValueError as err:
            raise PhysicsError(f"MuJoCo refused the model: {err}") from None
        self.data = mj.MjData(self.model)
        m = self.model
        self._qadr = {role: np.array([m.jnt_qposadr[m.joint(n).id] for n in names])
                      for role, names in self.physics.joints.items()}
        self._dadr = {role: np.array([m.jnt_dofadr[m.joint(n).id] for n in names])
                      for role, names in self.physics.joints.items()}
        self._arm_dofs = np.r_[self._dadr["leader"], self._dadr["follower"]]
        self._arm_q = np.r_[self._qadr["leader"], self._qadr["follower"]]
        self._obj_q = m.jnt_qposadr[m.joint("object_free").id]
        self.readout = Readout(m, self.data, self.physics, self.task)
        self._grasp_q = {r: (m.jnt_qposadr[m.joint(g.joint).id], g.rate)
                         for r, g in self.physics.grasps.items()}
        gap = self.physics.support_gap
        self._gap_q = None if gap is None else m.jnt_qposadr[m.joint(gap).id]
        n_l = len(self.physics.joints["leader"])
        self._n_l = n_l
        self._tau_max = np.r_[self.limits["leader"], self.limits["follower"]]

    def _place(self, state: DualArmState) -> None:
        """Set every coordinate from ``state`` (at rest) and compute the kinematics."""
        m, d, task = self.model, self.data, self.task
        d.qpos[:] = m.qpos0
        d.qvel[:] = 0.0
        d.qpos[self._qadr["leader"]] = state.q_l
        d.qpos[self._qadr["follower"]] = state.q_f
        T = task.object_pose(np.asarray(state.q_l), state.sigma_leader)
        quat = pin.Quaternion(T[:3, :3]).coeffs()
        d.qpos[self._obj_q:self._obj_q + 7] = np.r_[T[:3, 3], quat[3], quat[:3]]
        for role, (adr, rate) in self._grasp_q.items():
            sigma = state.sigma if role == "follower" else state.sigma_leader
            d.qpos[adr] = rate * sigma
        self._mj.mj_forward(m, d)

    def reset(self, state: DualArmState, dt: float) -> None:
        """Compile the model, leave out the pairs that overlap at ``state``, place it, settle.

        The joints are then as the servos hold them under the object's load
        (:meth:`_settle`), a little off ``state``: the first measured state.
        """
        xml = self.physics.xml
        self._compile(xml)
        self._place(state)
        m, d = self.model, self.data
        pairs = set()
        for c in d.contact[:d.ncon]:
            if c.dist < 0:
                b1, b2 = m.geom_bodyid[c.geom[0]], m.geom_bodyid[c.geom[1]]
                pairs.add(tuple(sorted((m.body(b1).name, m.body(b2).name))))
        if pairs:
            extra = "".join(f'<exclude body1="{a}" body2="{b}"/>' for a, b in sorted(pairs))
            self.notes.append("contact pairs left out because they overlap at the start: "
                              + ", ".join(f"{a} - {b}" for a, b in sorted(pairs)))
            self._compile(xml.replace("</contact>", extra + "</contact>"))
            self._place(state)
        self.substeps = max(1, math.ceil(dt / SUBSTEP - 1e-9))
        self.model.opt.timestep = dt / self.substeps
        self._set_gains()
        self.q_ref = np.r_[state.q_l, state.q_f].astype(float)
        self._rates = np.zeros(self.q_ref.size)
        #: The largest torque ratio, the joint (index over both arms) and the time [s].
        self.worst: tuple[float, int, float] = (0.0, -1, 0.0)
        self._settle()
        self.t = 0.0
        self.log = {k: [] for k in LOG_COLUMNS}
        self.log.update(w_leader=[], w_follower=[], torque=[], torque_peak=[], sigma=[])
        #: Each arm joint's velocity error ``qd - qd_ref`` at every substep [rad/s].
        self.velocity_error: list[FloatArray] = []
        #: Each arm joint's largest |torque| over the last sample's substeps [N m].
        self.peak_torque = np.zeros(self._arm_dofs.size)
        self._measured = self._measure(state.t)
        reading = self._record(state.t, state.sigma, 0.0)
        self._history = deque([(self._measured, reading)], maxlen=self.delay + 1)
        self._commands = CommandHistory(self.delay)
        self.readings = [reading]
        if self.measurement is not None:
            self.measurement.reset()
            self.measurement.update(reading, dt)

    def _set_gains(self) -> None:
        """Give each arm joint's servo its gains from the inertia at the start (:mod:`.gains`)."""
        mj, m, d = self._mj, self.model, self.data
        M = np.zeros((m.nv, m.nv))
        mj.mj_fullM(m, d, M)
        self.gains = servo_gains(M, self._dadr, self.settings, float(m.opt.timestep))
        set_gains(m, self.gains, self.settings.servo)

    def _settle(self) -> None:
        """Hold the start for :data:`SETTLE` s, so that the run starts from rest under load.

        The object is put into its grasps with no force on it; holding the joints while
        the servos take up its weight keeps that start-up out of the run's record. The
        object's free joint is left where the welds put it.
        """
        rest = np.zeros(self.q_ref.size)
        self._feedforward(self._measure(0.0))
        for _ in range(math.ceil(SETTLE / self.model.opt.timestep)):
            self._servo(rest)
            self._mj.mj_step(self.model, self.data)
        self._servo(rest)
        self._mj.mj_forward(self.model, self.data)
        self.check_stable("while the start settled", welds=True)

    def check_stable(self, when: str, *, welds: bool = False) -> None:
        """Raise :class:`DivergedError` if the simulation blew up.

        Blown up: a coordinate not finite, a joint faster than :data:`SPEED_DIVERGED`,
        MuJoCo's own instability warning (it then resets the state, which looks sound),
        or, with ``welds``, a weld's error beyond :data:`WELD_ERROR_DIVERGED`.
        """
        d = self.data
        reason = None
        if not (np.all(np.isfinite(d.qpos)) and np.all(np.isfinite(d.qvel))):
            reason = "a coordinate is not finite"
        elif np.abs(d.qvel).max(initial=0.0) > SPEED_DIVERGED:
            reason = f"a joint moves faster than {SPEED_DIVERGED:g} rad/s"
        elif d.warning[self._mj.mjtWarning.mjWARN_BADQACC].number > 0:
            reason = "MuJoCo found an infinite or huge acceleration and reset the state"
        elif welds:
            error = max(self.readout.weld_error(self.physics.welds[r])
                        for r in ("leader", "follower"))
            if error > WELD_ERROR_DIVERGED:
                reason = (f"a hand is {error * 1e3:.0f} mm off its grasp (a sound run keeps "
                          f"under {WELD_ERROR_DIVERGED * 1e3:g} mm)")
        if reason is None:
            return
        raise DivergedError(f"the simulation diverged {when}: {reason}. "
                            + unstable_gains_advice(self.settings, self.gains,
                                                    float(self.model.opt.timestep)))

    # -- stepping ---------------------------------------------------------------------
    def drive(self, rates: FloatArray, dt: float, q_ref: FloatArray | None = None, *,
              leak: bool = False) -> float:
        """Servo the arms at ``rates`` [rad/s] for ``dt``; return the peak torque ratio.

        The ratio is |torque| / limit, the largest of every joint's over the substeps;
        each joint's largest |torque| over them is left in :attr:`peak_torque` [N m],
        and each substep's ``qd - qd_ref`` is appended to :attr:`velocity_error`.

        ``q_ref`` resets the position reference first (a replay sets it to each recorded
        sample); otherwise it goes on from where the last call left it. With ``leak``
        the reference is also pulled towards the measured joints with the time constant
        ``settings.reference_time``.
        """
        mj, m, d = self._mj, self.model, self.data
        if q_ref is not None:
            self.q_ref = np.asarray(q_ref, dtype=float).copy()
        h = m.opt.timestep
        dofs = self._arm_dofs
        peak_tau = 0.0
        peak_abs = np.zeros(dofs.size)
        start, n = self._rates, self.substeps
        pull = h / self.settings.reference_time if leak else 0.0
        qadr = self._arm_q
        for i in range(n):
            self.q_ref = self.q_ref + h * rates + pull * (d.qpos[qadr] - self.q_ref)
            ramp = start + (i + 1) / n * (rates - start)
            self._servo(ramp)
            mj.mj_step(m, d)
            self.check_stable(f"at t = {self.t + (i + 1) * h:.4f} s")
            self.velocity_error.append(d.qvel[dofs] - ramp)
            torque = np.abs(d.qfrc_actuator[dofs] + d.qfrc_applied[dofs])
            np.maximum(peak_abs, torque, out=peak_abs)
            ratio = torque / self._tau_max
            if ratio.size and float(ratio.max()) > peak_tau:
                peak_tau = float(ratio.max())
                self.worst = max(self.worst, (peak_tau, int(np.argmax(ratio)), self.t))
        self._rates = np.asarray(rates, dtype=float).copy()
        self.peak_torque = peak_abs
        self.t += dt
        self.check_stable(f"at t = {self.t:.4f} s", welds=True)
        return peak_tau

    def _feedforward(self, state: DualArmState) -> None:
        """Set the load feed-forward at the measured ``state`` (:mod:`.statics`)."""
        self._ff = load_feedforward(self._load_task, state)

    def _servo(self, rates: FloatArray) -> None:
        """Set the servos' references and the arms' bias feed-forward."""
        d = self.data
        if self.settings.servo == "position":
            d.ctrl[0::2], d.ctrl[1::2] = self.q_ref, rates
        else:
            d.ctrl[:] = rates
        d.qfrc_applied[self._arm_dofs] = d.qfrc_bias[self._arm_dofs] + self._ff

    def advance(self, state: DualArmState, command: Command, dt: float) -> DualArmState:
        """Apply the command's rates for ``dt``; return the measured state (see the module).

        With :attr:`delay` ``d`` the state (and the reading appended to
        :attr:`readings`) is the one measured ``d`` samples ago (the start's, until
        there are ``d``), brought forward by the commands applied since when
        ``settings.predict`` (:mod:`dualarm_qp.control.predict`).
        """
        rates = np.r_[command.ql_dot, command.qf_dot]
        self._feedforward(self._measured)
        peak_tau = self.drive(rates, dt, leak=self.settings.reference == "measured")
        tau = state.t + dt * command.scale
        previous = self._measured
        self._measured = self._measure(tau)
        # The slip's reference: where the sample's command moved the grasp from where it
        # was at the sample's start, measured (previous), not from the state the controller
        # was handed (with delay older: its sliding since would count as slip).
        reading = self._record(tau, previous.sigma + dt * command.m, peak_tau)
        self._history.append((self._measured, reading))
        out, handed = self._history[0]
        self.readings.append(handed)
        if self.measurement is not None:
            self.measurement.update(handed, dt)
        self._commands.push(command, dt)
        late = DualArmState(tau, out.q_l, out.q_f, out.sigma, out.sigma_leader)
        if not self.settings.predict:
            return late
        return self._commands.predict(late, len(self._history) - 1)

    def replay_step(self, q_from: FloatArray, q_to: FloatArray, dt: float, tau: float,
                    sigma_ref: float) -> None:
        """Servo from the recorded joints ``q_from`` to ``q_to`` over ``dt``; record it.

        ``tau`` is the sample's path time [s], ``sigma_ref`` the recorded grasp [m].
        """
        rates = (np.asarray(q_to, dtype=float) - q_from) / dt
        self._feedforward(self._measure(tau))
        peak_tau = self.drive(rates, dt, q_ref=q_from)
        self._measured = self._measure(tau)
        self._record(tau, sigma_ref, peak_tau)

    # -- measuring --------------------------------------------------------------------
    def _measure(self, tau: float) -> DualArmState:
        d = self.data
        sig = {r: float(d.qpos[adr]) / rate for r, (adr, rate) in self._grasp_q.items()}
        return DualArmState(tau, d.qpos[self._qadr["leader"]].copy(),
                            d.qpos[self._qadr["follower"]].copy(), sig["follower"],
                            sig.get("leader", 0.0))

    def wrenches(self) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """Return the hands' wrenches on the object from the welds, and the grasp points.

        The simulator's own account of the forces (the welds' constraint forces); what
        the plant measures and hands on is the sensors' (:meth:`Readout.sensed
        <dualarm_qp.physics.readout.Readout.sensed>`).
        """
        return self.readout.welds()

    def _record(self, tau: float, sigma_ref: float, peak_tau: float) -> HandReading:
        """Log the sample just simulated; return its reading (:class:`HandReading`)."""
        d, log, ro, state = self.data, self.log, self.readout, self._measured
        log["t"].append(self.t)
        log["tau"].append(tau)
        dev = ro.deviation(self.task.trajectory.pose(tau))
        log["deviation_pos"].append(dev[0])
        log["deviation_rot"].append(dev[1])
        reading = ro.reading(state.sigma, state.sigma_leader)
        push = ro.spaces(state.sigma, state.sigma_leader)[2]
        log["internal"].append(reading.internal)
        log["support"].append(float(reading.follower[:3] @ push))
        log["share"].append(reading.share)
        share_plan, split = against_plan(self._load_task, state, reading, push)
        log["share_plan"].append(share_plan)
        log["split_error"].append(split)
        log["slip"].append(abs(state.sigma - sigma_ref))
        log["weld_leader"].append(ro.weld_error(self.physics.welds["leader"]))
        log["weld_follower"].append(ro.weld_error(self.physics.welds["follower"]))
        log["gap"].append(0.0 if self._gap_q is None else float(-d.qpos[self._gap_q]))
        tau_j = d.qfrc_actuator[self._arm_dofs] + d.qfrc_applied[self._arm_dofs]
        ratio = np.abs(tau_j) / self._tau_max
        peak = max(peak_tau, float(np.max(ratio))) if np.isfinite(self._tau_max).any() else np.nan
        log["torque_ratio_peak"].append(peak)
        log["w_leader"].append(reading.leader)
        log["w_follower"].append(reading.follower)
        log["torque"].append(tau_j.copy())
        log["torque_peak"].append(np.maximum(self.peak_torque, np.abs(tau_j)))
        log["sigma"].append(state.sigma)
        return dataclasses.replace(reading, torque_ratio=peak)

    def arrays(self) -> dict[str, FloatArray]:
        """Return the log as arrays (one row per controller sample)."""
        return {k: np.asarray(v, dtype=float) for k, v in self.log.items()}


__all__ = ["LOG_COLUMNS", "SETTLE", "SPEED_DIVERGED", "WELD_ERROR_DIVERGED", "DivergedError",
           "MujocoPlant", "PhysicsError", "simulated_task", "torque_limits"]
