"""The ROS 2 cell: two arms through ros2_control's topics, with plain rclpy.

Per arm (``cell.leader``, ``cell.follower`` of the experiment file):

* **state**: ``sensor_msgs/JointState`` on ``state_topic`` (default ``/joint_states``,
  as ``joint_state_broadcaster`` publishes it), mapped **by name** to the arm's
  ``joints`` (a message's order is not guaranteed; a message may carry other joints, or
  only some of the arm's). A joint's stamp is its message's header stamp (the receive
  time when a driver stamps zero); a reading's stamp is the **oldest** of both arms'
  joints, so that one arm whose state stops is seen by the watchdog. The loop reads
  the state **at each sample instant** (the newest stamped no later than it, waiting
  for it up to half a sample): a node that runs late still samples the arms on the
  sample grid;
* **command**: ``std_msgs/Float64MultiArray`` on ``<controller>/commands`` (a
  ``forward_command_controller`` over the arm's joints, in the order of ``joints``),
  each sample: the rates [rad/s] with ``interface: velocity``; with ``interface:
  position``, the positions [rad] the rates reach at the next sample, integrated from the
  positions measured when the cell opened. The controller holds a command until the
  next (``between = "held"``).

The cell's clock is the node's ROS clock: the system clock, or with ``use_sim_time`` a
simulator's ``/clock``; the joint states are stamped on it (``joint_state_broadcaster``
stamps with the controller manager's time), so the watchdog measures their age there.
A clock that stands still for :data:`CLOCK_STALL` seconds of wall time (a simulator
that stopped) stops the cell.

Each recorded sample is also published (:meth:`Ros2Cell.observe`, the drive loop's
observer): the grasp as a virtual joint in the node's own ``~/joint_states``, the object
carried by the leader, ``D(t)`` and the grasp point on ``/tf`` (when tf2_msgs is
installed, as it is with every ROS 2 installation) and the step's status on
``/diagnostics``.
"""

from __future__ import annotations

import math
import time
from collections import deque
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..bag.stream import (
    DIAGNOSTIC_KEYS,
    Sample,
    StreamNames,
    diagnostic_level,
    frames,
    quaternion_xyzw,
)
from ..control.trace import Trace
from ..experiments.config import ExperimentConfig
from ..experiments.setup import Experiment
from ..task.scene import DualArmTask
from .base import CellError, CellSetupError, Reading
from .ros2_node import Ros2Node

FloatArray = NDArray[np.float64]

#: Wall time [s] the cell waits for the first joint states and the controllers.
CONNECT_TIMEOUT = 30.0
#: Wall time [s] the ROS clock may stand still before the cell stops.
CLOCK_STALL = 2.0
#: Longest wall time [s] the cell waits, when it closes, for the controllers to
#: acknowledge its last commands.
CLOSE_WAIT = 2.0
#: Longest wait [s] of one spin of the node (an interrupt is seen within it).
SPIN = 0.005
#: Longest wall time [s] a read waits for the state of its sample instant (a clock
#: that waits for the node, as a simulator in step with it does, does not advance).
READ_WAIT = 0.1


@dataclass(frozen=True)
class ArmTopics:
    """One arm's names and topics.

    Attributes
    ----------
    role : str
        ``"leader"`` or ``"follower"``.
    joints : tuple of str
        The robot's joint names, in the arm's order.
    state_topic : str
        Where its joint states come from.
    command_topic : str or None
        ``<controller>/commands`` (None: no streaming controller named).
    trajectory_topic : str or None
        ``<trajectory_controller>/joint_trajectory``.
    """

    role: str
    joints: tuple[str, ...]
    state_topic: str
    command_topic: str | None
    trajectory_topic: str | None


@dataclass(frozen=True)
class Ros2Settings:
    """The ROS 2 cell's settings, from the ``cell:`` section (see the module)."""

    arms: tuple[ArmTopics, ArmTopics]
    interface: str
    node: str
    use_sim_time: bool
    dt: float


def ros2_settings(cfg: ExperimentConfig, exp: Experiment, path: str, *,
                  need: str = "controller") -> Ros2Settings:
    """Return the cell's settings from the file, checked.

    Parameters
    ----------
    need : {"controller", "trajectory_controller", ""}
        The controller every arm must name (``""``: none, a dry run).

    Raises
    ------
    CellSetupError
        An arm without joint names, with as many as its joints, or without the
        controller needed.
    """
    arms = []
    for role, arm in (("leader", exp.task.leader), ("follower", exp.task.follower)):
        spec = getattr(cfg.cell, role)
        if spec.joints is None or len(spec.joints) != arm.n:
            got = "none" if spec.joints is None else f"{len(spec.joints)}"
            raise CellSetupError(f"{path}: cell.{role}.joints: the ROS 2 cell maps the joint "
                                 f"states by name: give the arm's {arm.n} joint names "
                                 f"(got {got})")
        if need and getattr(spec, need) is None:
            kind = ("forward_command_controller" if need == "controller"
                    else "joint_trajectory_controller")
            raise CellSetupError(f"{path}: cell.{role}.{need}: name the arm's {kind}")
        arms.append(ArmTopics(role, tuple(spec.joints), spec.state_topic,
                              None if spec.controller is None
                              else spec.controller.rstrip("/") + "/commands",
                              None if spec.trajectory_controller is None
                              else spec.trajectory_controller.rstrip("/") + "/joint_trajectory"))
    return Ros2Settings((arms[0], arms[1]), cfg.cell.interface, cfg.cell.node,
                        cfg.cell.use_sim_time, exp.options.dt)


class JointStates:
    """The position and stamp of every joint of both arms, mapped by name, with a history.

    Each ``JointState`` that carries joints of the arms updates them; the readings after
    the last :data:`HISTORY` of them are kept, so that the state at a sample's instant
    can be had after it (:meth:`reading`).
    """

    #: How many readings are kept.
    HISTORY = 64

    def __init__(self, arms: tuple[ArmTopics, ArmTopics]) -> None:
        self.arms = arms
        self.q = [np.full(len(a.joints), np.nan) for a in arms]
        self.stamp = [np.full(len(a.joints), -math.inf) for a in arms]
        self.index = {name: (i, j) for i, a in enumerate(arms) for j, name in enumerate(a.joints)}
        self.history: deque[Reading] = deque(maxlen=self.HISTORY)

    def update(self, names: Any, positions: Any, stamp: float) -> None:
        """Take the joints of one ``JointState`` that belong to the arms."""
        hit = False
        for name, value in zip(names, positions, strict=False):
            where = self.index.get(name)
            if where is not None:
                i, j = where
                self.q[i][j] = value
                self.stamp[i][j] = stamp
                hit = True
        if hit and not self.missing():
            self.history.append(self.newest())

    @property
    def newest_t(self) -> float:
        """The stamp of the newest reading [s] (-inf before the first)."""
        return self.history[-1].t if self.history else -math.inf

    def missing(self) -> list[str]:
        """Return the joints not heard of yet."""
        return [name for i, a in enumerate(self.arms) for j, name in enumerate(a.joints)
                if not math.isfinite(self.stamp[i][j])]

    def newest(self) -> Reading:
        """Return both arms' newest joints, stamped with the oldest joint's stamp."""
        t = float(min(np.min(s) for s in self.stamp))
        return Reading(t, self.q[0].copy(), self.q[1].copy())

    def reading(self, at: float | None = None) -> Reading:
        """Return the reading at ``at`` [s]: the newest stamped no later (None: the newest).

        When every kept reading is newer, the oldest kept.
        """
        if at is None or not self.history:
            return self.newest()
        tol = 1e-9 * max(1.0, abs(at))
        for r in reversed(self.history):
            if r.t <= at + tol:
                return r
        return self.history[0]


class Ros2Cell:
    """Two arms through ros2_control (see the module).

    Parameters
    ----------
    settings : Ros2Settings
        Topics, names, interface, clock.
    task : DualArmTask
        The task (the published object pose, ``D(t)`` and grasp point).
    names : StreamNames
        The names of the published grasp joints.
    dry_run : bool
        Send nothing: no command topic is needed.
    trajectories : bool
        Publish to each arm's ``joint_trajectory_controller`` instead (the publishers
        :attr:`publishers`, ``trajectory_msgs/JointTrajectory``; :mod:`.ros2_trajectory`).
    """

    kind = "ros2"
    between = "held"

    def __init__(self, settings: Ros2Settings, task: DualArmTask, names: StreamNames, *,
                 dry_run: bool = False, trajectories: bool = False) -> None:
        self.settings = settings
        self.task = task
        self.names = names
        self.dry_run = dry_run
        self.trajectories = trajectories
        self.node: Ros2Node | None = None
        self.states = JointStates(settings.arms)
        self._commands: list[Any] = []
        self._position: list[FloatArray] = []
        self._pub: dict[str, Any] = {}
        self._sample_t: float | None = None

    # -- connecting -------------------------------------------------------------------
    def _on_state(self, msg: Any) -> None:
        stamp = msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9
        if stamp == 0.0 and self.node is not None:
            stamp = self.node.now()
        self.states.update(msg.name, msg.position, stamp)

    def _waiting_for(self) -> str:
        """Return what the cell still waits for before it can run ('' when nothing)."""
        assert self.node is not None
        if self.settings.use_sim_time and self.node.now() == 0.0:
            return "the first /clock message (use_sim_time is on)"
        missing = self.states.missing()
        if missing:
            topics = sorted({a.state_topic for a in self.settings.arms})
            return (f"joint states of {', '.join(missing[:3])}"
                    f"{' and more' if len(missing) > 3 else ''} on {', '.join(topics)}")
        for pub in self._commands:
            if pub.get_subscription_count() == 0:
                return f"a controller listening on {pub.topic_name}"
        return ""

    def open(self) -> Reading:
        """Create the node, wait for the joint states and the controllers; return a reading.

        Raises
        ------
        CellError
            Nothing came within :data:`CONNECT_TIMEOUT` seconds.
        """
        s = self.settings
        node = self.node = Ros2Node(s.node, use_sim_time=s.use_sim_time)
        t = node.types
        for topic in sorted({a.state_topic for a in s.arms}):
            node.subscribe(t.JointState, topic, self._on_state)
        if self.trajectories:
            self._commands = [node.publisher(t.JointTrajectory, str(a.trajectory_topic))
                              for a in s.arms]
        elif not self.dry_run:
            self._commands = [node.publisher(t.Float64MultiArray, str(a.command_topic))
                              for a in s.arms]
        self._pub = {"joints": node.publisher(t.JointState, "~/joint_states"),
                     "diagnostics": node.publisher(t.DiagnosticArray, "/diagnostics")}
        if t.tf is not None:
            self._pub["tf"] = node.publisher(t.tf, "/tf")
        deadline = time.monotonic() + CONNECT_TIMEOUT
        while (waiting := self._waiting_for()):
            if time.monotonic() > deadline:
                raise CellError(f"no answer from the ROS 2 graph within {CONNECT_TIMEOUT:g} "
                                f"s: waiting for {waiting} (is the controller manager "
                                "running, with the same ROS_DOMAIN_ID?)")
            node.spin_once(0.05)
        first = self.states.newest()
        self._position = [first.q_l.copy(), first.q_f.copy()]
        return first

    # -- the cell's interface ---------------------------------------------------------
    def read(self) -> Reading:
        """Return both arms' joints at the last sample instant waited for (see the module).

        Waits for the state of that instant up to half a sample on the ROS clock (and
        :data:`READ_WAIT` of wall time); a state that does not come by then is not
        waited for (the watchdog judges its age).
        """
        assert self.node is not None
        at = self._sample_t
        if at is not None:
            give_up = at + 0.5 * self.settings.dt
            stall = time.monotonic() + READ_WAIT
            while (self.states.newest_t < at - 1e-9 * max(1.0, abs(at))
                   and self.node.now() < give_up and time.monotonic() < stall):
                self.node.spin_once(SPIN)
        self.node.spin_once(0.0)
        return self.states.reading(at)

    def now(self) -> float:
        """Return the node's ROS clock [s]."""
        assert self.node is not None
        return self.node.now()

    @property
    def publishers(self) -> list[Any]:
        """The leader's and the follower's command publishers (none in a dry run)."""
        return list(self._commands)

    def send(self, ql_dot: FloatArray, qf_dot: FloatArray) -> None:
        """Publish both arms' commands (rates, or the positions they reach: see the module)."""
        if not self._commands or self.trajectories:
            return
        msg_type = self._node_types().Float64MultiArray
        for i, (pub, rates) in enumerate(zip(self._commands, (ql_dot, qf_dot), strict=True)):
            rates = np.asarray(rates, dtype=np.float64)
            if self.settings.interface == "position":
                self._position[i] = self._position[i] + rates * self.settings.dt
                values = self._position[i]
            else:
                values = rates
            pub.publish(msg_type(data=[float(v) for v in values]))

    def wait_until(self, t: float) -> None:
        """Spin the node until its clock reaches ``t`` [s].

        Raises
        ------
        CellError
            The clock stood still for :data:`CLOCK_STALL` seconds of wall time.
        """
        assert self.node is not None
        last = self.node.now()
        stall = time.monotonic() + CLOCK_STALL
        while (now := self.node.now()) < t - 1e-9 * max(1.0, abs(t)):
            if now > last:
                last, stall = now, time.monotonic() + CLOCK_STALL
            elif time.monotonic() > stall:
                raise CellError(f"the ROS clock stopped at {now:.4f} s (no progress for "
                                f"{CLOCK_STALL:g} s): is the simulator or driver still "
                                "running?")
            self.node.spin_once(min(SPIN, max(t - now, 0.0)))
        self._sample_t = t

    def close(self) -> None:
        """Destroy the node once the controllers have its last commands.

        It waits at most :data:`CLOSE_WAIT` for their acknowledgement: the stop's last
        command, at rest, must not be lost with the node, as a controller holds the last
        command it heard.
        """
        if self.node is not None:
            node, self.node = self.node, None
            from rclpy.duration import Duration

            for pub in self._commands:
                pub.wait_for_all_acked(Duration(seconds=CLOSE_WAIT))
            node.close()

    # -- what the node publishes ------------------------------------------------------
    def _node_types(self) -> Any:
        assert self.node is not None
        return self.node.types

    def observe(self, trace: Trace, k: int) -> None:
        """Publish row ``k`` of the drive's record: grasp, frames, status (see the module)."""
        if self.node is None:
            return
        s = Sample.from_trace(trace, k)
        t = self.node.types
        stamp = self.node.node.get_clock().now().to_msg()  # the ROS clock: tf's time base
        n = len(self.names.grasps)
        grasp = t.JointState(name=list(self.names.grasps),
                             position=[float(v) for v in s.positions(n)[-n:]],
                             velocity=[float(v) for v in s.velocities(n)[-n:]])
        grasp.header.stamp = stamp
        self._pub["joints"].publish(grasp)
        status = t.DiagnosticStatus(
            level=bytes([diagnostic_level(s.status)]), name=f"{self.settings.node}: step",
            message=s.status, hardware_id="dualarm_qp",
            values=[t.KeyValue(key=key, value=repr(s.values[key])) for key in DIAGNOSTIC_KEYS])
        diag = t.DiagnosticArray(status=[status])
        diag.header.stamp = stamp
        self._pub["diagnostics"].publish(diag)
        if "tf" in self._pub:
            self._pub["tf"].publish(self._tf(s, stamp))

    def _tf(self, s: Sample, stamp: Any) -> Any:
        t = self._node_types()
        out = []
        for parent, child, T in frames(self.task, s).transforms():
            msg = t.TransformStamped(child_frame_id=child)
            msg.header.stamp, msg.header.frame_id = stamp, parent
            tr = msg.transform
            tr.translation.x, tr.translation.y, tr.translation.z = (float(v) for v in T[:3, 3])
            q = quaternion_xyzw(T[:3, :3])
            tr.rotation.x, tr.rotation.y, tr.rotation.z, tr.rotation.w = (float(v) for v in q)
            out.append(msg)
        return t.tf(transforms=out)


def ros2_cell(cfg: ExperimentConfig, exp: Experiment, path: str, *, dry_run: bool = False
              ) -> Ros2Cell:
    """Return the experiment's ROS 2 cell (not yet opened; see the module).

    Raises
    ------
    CellSetupError
        rclpy is missing, or the ``cell:`` section lacks what the cell needs.
    """
    from .ros2_node import ros_types

    settings = ros2_settings(cfg, exp, path, need="" if dry_run else "controller")
    ros_types()  # refuse at once (bad input) when rclpy is missing
    names = StreamNames.of(exp.task, cfg.cell.leader.joints, cfg.cell.follower.joints,
                           path=path)
    return Ros2Cell(settings, exp.task, names, dry_run=dry_run)


__all__ = ["CLOCK_STALL", "CLOSE_WAIT", "CONNECT_TIMEOUT", "ArmTopics", "JointStates", "Ros2Cell",
           "Ros2Settings", "ros2_cell", "ros2_settings"]
