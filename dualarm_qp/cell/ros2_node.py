"""The ROS 2 node the ROS 2 cell speaks through: plain rclpy, imported only here.

The project's own environment has no rclpy: it comes from a ROS 2 installation (Jazzy
or later; ``source /opt/ros/<distro>/setup.bash`` puts it on ``PYTHONPATH``) or from
community wheels in an environment of their own (``docs/ros2.md``). Nothing else of
the package imports rclpy, and this module only when a ROS 2 cell is opened.

:class:`Ros2Node` is one node in a context of its own, spun by a single-threaded
executor from the caller's thread (:meth:`Ros2Node.spin_once`): every callback runs
inside the cell's own calls, never beside them. rclpy's signal handlers are not
installed: Ctrl-C and SIGTERM stay the drive loop's (the arms are brought to rest
through the node before it is closed).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from .base import CellSetupError

#: What to do when rclpy cannot be imported.
ROS_MISSING = ("the ROS 2 cell needs rclpy and the message packages (sensor_msgs, std_msgs, "
               "trajectory_msgs, diagnostic_msgs): source your ROS 2 installation first "
               "(source /opt/ros/jazzy/setup.bash), or see docs/ros2.md")


@dataclass(frozen=True)
class RosTypes:
    """The message types the cell uses (``tf`` is None when tf2_msgs is not installed)."""

    JointState: Any
    Float64MultiArray: Any
    JointTrajectory: Any
    JointTrajectoryPoint: Any
    DiagnosticArray: Any
    DiagnosticStatus: Any
    KeyValue: Any
    TransformStamped: Any
    Duration: Any
    Time: Any
    tf: Any


def ros_types() -> RosTypes:
    """Import rclpy's message types.

    Raises
    ------
    CellSetupError
        rclpy or a message package is missing.
    """
    try:
        import rclpy  # noqa: F401  (the message types need its library loaded)
        from builtin_interfaces.msg import Duration, Time
        from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
        from geometry_msgs.msg import TransformStamped
        from sensor_msgs.msg import JointState
        from std_msgs.msg import Float64MultiArray
        from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint
    except ImportError as err:
        raise CellSetupError(f"{ROS_MISSING} ({err})") from None
    try:
        from tf2_msgs.msg import TFMessage
    except ImportError:  # every ROS 2 installation has it; some wheel sets do not
        TFMessage = None
    return RosTypes(JointState, Float64MultiArray, JointTrajectory, JointTrajectoryPoint,
                    DiagnosticArray, DiagnosticStatus, KeyValue, TransformStamped, Duration,
                    Time, TFMessage)


class Ros2Node:
    """One rclpy node in a context of its own (see the module).

    Parameters
    ----------
    name : str
        The node's name.
    use_sim_time : bool
        Take the node's clock from ``/clock``.

    Raises
    ------
    CellSetupError
        rclpy is missing, or the node cannot be created (a bad name).
    """

    def __init__(self, name: str, *, use_sim_time: bool) -> None:
        self.types = ros_types()
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.parameter import Parameter
        from rclpy.signals import SignalHandlerOptions

        self._rclpy = rclpy
        self.context = rclpy.context.Context()
        rclpy.init(context=self.context, signal_handler_options=SignalHandlerOptions.NO)
        try:
            self.node = rclpy.create_node(
                name, context=self.context,
                parameter_overrides=[Parameter("use_sim_time", value=use_sim_time)])
        except Exception as err:  # rclpy's InvalidNodeNameException and kin
            rclpy.shutdown(context=self.context)
            raise CellSetupError(f"cell.node: cannot create the ROS 2 node {name!r}: "
                                 f"{err}") from None
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)

    def now(self) -> float:
        """Return the node's clock [s] (``/clock`` with ``use_sim_time``)."""
        return float(self.node.get_clock().now().nanoseconds) * 1e-9

    def spin_once(self, timeout: float) -> None:
        """Run at most one ready callback, waiting up to ``timeout`` [s] for one."""
        self.executor.spin_once(timeout_sec=timeout)

    def publisher(self, msg_type: Any, topic: str, *, latched: bool = False) -> Any:
        """Return a reliable publisher (``latched``: kept for late subscribers)."""
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

        qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE,
                         durability=(DurabilityPolicy.TRANSIENT_LOCAL if latched
                                     else DurabilityPolicy.VOLATILE))
        return self.node.create_publisher(msg_type, topic, qos)

    def subscribe(self, msg_type: Any, topic: str, callback: Callable[[Any], None]) -> Any:
        """Subscribe best effort (it hears reliable and best-effort publishers alike)."""
        from rclpy.qos import qos_profile_sensor_data

        return self.node.create_subscription(msg_type, topic, callback,
                                             qos_profile_sensor_data)

    def resolve(self, topic: str) -> str:
        """Return the full name of ``topic`` as this node resolves it."""
        return str(self.node.resolve_topic_name(topic))

    def close(self) -> None:
        """Destroy the node and shut its context down."""
        try:
            self.executor.remove_node(self.node)
            self.node.destroy_node()
            self.executor.shutdown(timeout_sec=1.0)
        finally:
            if self.context.ok():
                self._rclpy.shutdown(context=self.context)


__all__ = ["ROS_MISSING", "Ros2Node", "RosTypes", "ros_types"]
