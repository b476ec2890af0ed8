"""The stream's topics and the live view's address (plain values, nothing imported).

The command line's parser reads them (``dualarm-qp bag --port``), so they live apart
from the stream (NumPy) and its serialization (rosbags).
"""

from __future__ import annotations

#: The stream's topics and their message types.
TOPICS: dict[str, str] = {
    "/joint_states": "sensor_msgs/msg/JointState",
    "/tf": "tf2_msgs/msg/TFMessage",
    "/diagnostics": "diagnostic_msgs/msg/DiagnosticArray",
    "/dualarm/summary": "std_msgs/msg/String",
}

#: The address the live view is served on: this machine only.
HOST = "127.0.0.1"
#: Foxglove's default port.
DEFAULT_PORT = 8765

__all__ = ["DEFAULT_PORT", "HOST", "TOPICS"]
