"""A stand-in for ros2_control, for the tests: plain rclpy, run in the ROS environment.

It plays a controller manager with, per arm, a ``forward_command_controller``
(``<controller>/commands``, ``std_msgs/Float64MultiArray``, velocity or position
interface) and a ``joint_trajectory_controller`` (``<controller>/joint_trajectory``),
and a ``joint_state_broadcaster`` (``/joint_states``, every joint of both arms and one
joint of neither, in a shuffled order). It runs on a simulated clock of its own,
published on ``/clock``: each tick advances it by ``period`` seconds and integrates the
commands over it (velocity: ``q += v period``; position: ``q = command``; a trajectory:
positions interpolated linearly between its points, from its header stamp on).

The clock ticks every ``wall_period`` seconds of wall time, except in ``lockstep``
(a simulator in step with its controller, as MuJoCo is in the project's MuJoCo cell):
there it stands still (its state and clock published again every ``wall_period``),
and each command to every forward controller lets it run one controller sample
(``dt``), so a busy machine delays the whole simulation rather than the commands within
it.

``freeze_after`` [s of its clock]: that long after the first command it publishes no
more joint states (its clock goes on), as a broadcaster that stopped. Everything it did
and heard is logged, one JSON object a line, on its own clock: ``{"t", "q"}`` every
tick, ``{"t", "command", "data"}`` per command, ``{"t", "trajectory", "stamp", "times",
"positions"}`` per trajectory, ``{"t", "heard", ...}`` per message of the node under
test (its grasp joints and its diagnostics).

Usage: ``python standin.py SPEC.json`` (see ``tests/ros2/conftest.py``); SIGTERM or
SIGINT ends it.
"""

from __future__ import annotations

import json
import random
import signal
import sys
import time

import rclpy
from diagnostic_msgs.msg import DiagnosticArray
from rclpy.qos import qos_profile_sensor_data
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from trajectory_msgs.msg import JointTrajectory

OTHER_JOINT = "gripper_finger_joint"


class StandIn:
    def __init__(self, spec: dict) -> None:
        self.spec = spec
        self.names = list(spec["joints"])
        self.q = {n: float(v) for n, v in spec["joints"].items()}
        self.v = dict.fromkeys(self.names, 0.0)
        self.t_ns = 0
        self.period_ns = round(spec["period"] * 1e9)
        self.lockstep = bool(spec.get("lockstep", False))
        self.sample_ticks = round(spec.get("dt", spec["period"]) / spec["period"])
        self.pending: set[str] = set()
        self.allowed = 0
        self.freeze_after = spec.get("freeze_after")
        self.freeze_ns: int | None = None
        self.interface = spec.get("interface", "velocity")
        self.order = [*self.names, OTHER_JOINT]
        random.Random(0).shuffle(self.order)
        self.trajectories: dict[str, tuple[int, list[float], list[float]]] = {}
        self.log = open(spec["log"], "w", buffering=1)  # one line at a time
        self.node = rclpy.create_node("standin")
        self.clock_pub = self.node.create_publisher(Clock, "/clock", 10)
        self.js_pub = self.node.create_publisher(JointState, "/joint_states", 10)
        for controller, joints in spec["controllers"].items():
            self.node.create_subscription(
                Float64MultiArray, controller + "/commands",
                lambda msg, c=controller, j=joints: self.on_command(c, j, msg), 10)
        for controller in spec.get("trajectory_controllers", {}):
            self.node.create_subscription(
                JointTrajectory, controller + "/joint_trajectory",
                lambda msg, c=controller: self.on_trajectory(c, msg), 10)
        self.node.create_subscription(JointState, "/dualarm_qp/joint_states", self.on_grasp,
                                      qos_profile_sensor_data)
        self.node.create_subscription(DiagnosticArray, "/diagnostics", self.on_diagnostics, 10)

    def write(self, **entry) -> None:
        self.log.write(json.dumps({"t": self.t_ns * 1e-9, **entry}) + "\n")

    def on_command(self, controller: str, joints: list[str], msg) -> None:
        data = [float(x) for x in msg.data]
        self.write(command=controller, data=data)
        if self.freeze_after is not None and self.freeze_ns is None:
            self.freeze_ns = self.t_ns + round(self.freeze_after * 1e9)
            self.write(freeze_at=self.freeze_ns * 1e-9)
        self.pending.add(controller)
        if self.pending >= set(self.spec["controllers"]):
            self.pending.clear()
            self.allowed += self.sample_ticks  # one sample more
        if len(data) != len(joints):
            return  # as ros2_control does: a command of the wrong size is dropped
        for name, value in zip(joints, data, strict=True):
            if self.interface == "velocity":
                self.v[name] = value
            else:
                self.q[name] = value
                self.v[name] = 0.0

    def on_trajectory(self, controller: str, msg) -> None:
        stamp = msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec
        times = [p.time_from_start.sec + p.time_from_start.nanosec * 1e-9 for p in msg.points]
        positions = [[float(x) for x in p.positions] for p in msg.points]
        self.write(trajectory=controller, stamp=stamp * 1e-9, names=list(msg.joint_names),
                   times=times, positions=positions)
        if not msg.points:  # an empty trajectory: hold where the joints are
            for name in msg.joint_names:
                self.trajectories.pop(name, None)
            return
        start = stamp if stamp else self.t_ns
        for j, name in enumerate(msg.joint_names):
            self.trajectories[name] = (start, times, [p[j] for p in positions])
            self.v[name] = 0.0

    def on_grasp(self, msg) -> None:
        self.write(heard="grasp", names=list(msg.name), position=list(msg.position))

    def on_diagnostics(self, msg) -> None:
        for s in msg.status:
            self.write(heard="diagnostics", level=int.from_bytes(s.level, "little"),
                       message=s.message)

    def _follow(self, name: str) -> None:
        start, times, values = self.trajectories[name]
        tau = (self.t_ns - start) * 1e-9
        if tau <= times[0]:
            return
        if tau >= times[-1]:
            self.q[name] = values[-1]
            return
        k = next(i for i in range(1, len(times)) if times[i] >= tau)
        w = (tau - times[k - 1]) / (times[k] - times[k - 1])
        self.q[name] = values[k - 1] + w * (values[k] - values[k - 1])

    def tick(self, advance: bool = True) -> None:
        if advance:
            self.t_ns += self.period_ns
            for name in self.names:
                if name in self.trajectories:
                    self._follow(name)
                else:
                    self.q[name] += self.v[name] * self.period_ns * 1e-9
        stamp = rclpy.time.Time(nanoseconds=self.t_ns).to_msg()
        if advance:
            self.write(q=[self.q[n] for n in self.names])
        if self.freeze_ns is None or self.t_ns < self.freeze_ns:
            msg = JointState(name=self.order,
                             position=[self.q.get(n, 0.25) for n in self.order],
                             velocity=[self.v.get(n, 0.0) for n in self.order])
            msg.header.stamp = stamp
            self.js_pub.publish(msg)
        self.clock_pub.publish(Clock(clock=stamp))  # after the state of the same instant

    def run(self) -> None:
        wall = self.spec["wall_period"]
        next_tick = time.monotonic()
        while rclpy.ok():
            now = time.monotonic()
            if self.lockstep and self.allowed > 0:
                self.tick()
                self.allowed -= 1
                next_tick = now + wall
                rclpy.spin_once(self.node, timeout_sec=0.0)
                continue
            if now >= next_tick:
                self.tick(advance=not self.lockstep or self.t_ns == 0)
                next_tick = max(next_tick + wall, now - wall)
            rclpy.spin_once(self.node, timeout_sec=max(0.0, min(next_tick - now, wall)))


def main() -> None:
    with open(sys.argv[1]) as fh:
        spec = json.load(fh)
    rclpy.init(signal_handler_options=rclpy.signals.SignalHandlerOptions.NO)
    stand_in = StandIn(spec)

    def stop(signum, frame):
        raise SystemExit(0)

    signal.signal(signal.SIGTERM, stop)
    signal.signal(signal.SIGINT, stop)
    print("ready", flush=True)
    try:
        stand_in.run()
    finally:
        stand_in.log.close()


if __name__ == "__main__":
    main()
