"""The stream's ROS 2 messages, serialized as ROS 2 does (CDR), without ROS.

:class:`CdrMessages` turns each :class:`~.stream.Sample` into the messages of the
stream's topics (:data:`~.topics.TOPICS`), serialized with rosbags' type store of ROS 2
Jazzy: the bytes a ROS 2 publisher sends, which a bag stores and a Foxglove live view
serves as they are. The timestamp of every message, and its header stamp, is the row's
``t``.
"""

from __future__ import annotations

import functools
import json
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..task.scene import DualArmTask
from .stream import DIAGNOSTIC_KEYS, Sample, StreamNames, diagnostic_level, frames, quaternion_xyzw
from .topics import TOPICS

#: The name of every sample's diagnostic status.
DIAGNOSTIC_NAME = "dualarm_qp: step"


@functools.cache
def typestore() -> Any:
    """Return rosbags' type store of ROS 2 Jazzy (one per process: it compiles its types).

    Raises
    ------
    InvalidInputError
        rosbags is not installed.
    """
    try:
        from rosbags.typesys import Stores, get_typestore
    except ImportError:
        from ..errors import InvalidInputError

        raise InvalidInputError('a bag needs rosbags: pip install "dualarm-qp[bag]"') from None
    return get_typestore(Stores.ROS2_JAZZY)


def message_definition(store: Any, msgtype: str) -> str:
    """Return the ROS 2 message definition of ``msgtype`` (with its nested types)."""
    return str(store.generate_msgdef(msgtype, ros_version=2)[0])


@dataclass(frozen=True)
class Message:
    """One serialized message of the stream."""

    topic: str
    stamp_ns: int
    data: bytes


class CdrMessages:
    """The messages of a run's samples (see the module).

    Parameters
    ----------
    task : DualArmTask
        The run's task (the object pose and ``D(t)`` are computed from it).
    names : StreamNames
        The joints' names.
    store : rosbags Typestore, optional
        Default: :func:`typestore`.
    """

    def __init__(self, task: DualArmTask, names: StreamNames, store: Any = None) -> None:
        self.task = task
        self.names = names
        self.store = typestore() if store is None else store
        t = self.store.types
        self._js, self._header, self._time = (t["sensor_msgs/msg/JointState"],
                                              t["std_msgs/msg/Header"],
                                              t["builtin_interfaces/msg/Time"])
        self._tf, self._ts, self._tr = (t["tf2_msgs/msg/TFMessage"],
                                        t["geometry_msgs/msg/TransformStamped"],
                                        t["geometry_msgs/msg/Transform"])
        self._vec, self._quat = t["geometry_msgs/msg/Vector3"], t["geometry_msgs/msg/Quaternion"]
        self._diag, self._status, self._kv = (t["diagnostic_msgs/msg/DiagnosticArray"],
                                              t["diagnostic_msgs/msg/DiagnosticStatus"],
                                              t["diagnostic_msgs/msg/KeyValue"])
        self._string = t["std_msgs/msg/String"]

    def _stamp(self, ns: int) -> Any:
        return self._time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)

    def _serialize(self, message: Any) -> bytes:
        return bytes(self.store.serialize_cdr(message, message.__msgtype__))

    def joint_state(self, s: Sample) -> Any:
        """Return the joint state of ``s``: both arms, then the grasps (see :mod:`.stream`)."""
        n = len(self.names.grasps)
        return self._js(header=self._header(stamp=self._stamp(s.stamp_ns), frame_id=""),
                        name=list(self.names.joints), position=s.positions(n),
                        velocity=s.velocities(n), effort=np.zeros(0))

    def tf(self, s: Sample) -> Any:
        """Return the transforms of ``s`` (object, target ``D(t)``, grasp point)."""
        stamp = self._stamp(s.stamp_ns)
        out = []
        for parent, child, T in frames(self.task, s).transforms():
            x, y, z, w = quaternion_xyzw(T[:3, :3])
            out.append(self._ts(
                header=self._header(stamp=stamp, frame_id=parent), child_frame_id=child,
                transform=self._tr(translation=self._vec(x=float(T[0, 3]), y=float(T[1, 3]),
                                                         z=float(T[2, 3])),
                                   rotation=self._quat(x=x, y=y, z=z, w=w))))
        return self._tf(transforms=out)

    def diagnostics(self, s: Sample) -> Any:
        """Return the step's status of ``s`` with the values the run judges."""
        values = [self._kv(key=key, value=repr(s.values[key])) for key in DIAGNOSTIC_KEYS]
        status = self._status(level=diagnostic_level(s.status), name=DIAGNOSTIC_NAME,
                              message=s.status, hardware_id="dualarm_qp", values=values)
        return self._diag(header=self._header(stamp=self._stamp(s.stamp_ns), frame_id=""),
                          status=[status])

    def sample(self, s: Sample) -> list[Message]:
        """Return the serialized messages of one sample: joints, transforms, status."""
        return [Message("/joint_states", s.stamp_ns, self._serialize(self.joint_state(s))),
                Message("/tf", s.stamp_ns, self._serialize(self.tf(s))),
                Message("/diagnostics", s.stamp_ns, self._serialize(self.diagnostics(s)))]

    def summary(self, summary: Mapping[str, Any], stamp_ns: int) -> Message:
        """Return the run's ``summary.json`` as one ``std_msgs/String`` (JSON text)."""
        text = json.dumps(summary, sort_keys=True)
        return Message("/dualarm/summary", stamp_ns, self._serialize(self._string(data=text)))


__all__ = ["DIAGNOSTIC_NAME", "TOPICS", "CdrMessages", "Message", "message_definition",
           "typestore"]
