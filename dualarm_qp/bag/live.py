"""The stream served live to Foxglove: a run replayed, or a drive as it happens.

:class:`LiveView` is a Foxglove WebSocket server (foxglove-sdk, protocol
``foxglove.sdk.v1``) on 127.0.0.1 with one channel per topic of the stream
(:data:`~.topics.TOPICS`), each carrying the ROS 2 messages as a ROS 2 publisher
sends them (``cdr``, with ``ros2msg`` schemas): the bytes a bag holds. The Foxglove app
connects to ``ws://127.0.0.1:PORT`` (its "Foxglove WebSocket" connection).

* :func:`replay` serves a finished run (``dualarm-qp bag RUN_DIR --foxglove``) at the
  pace of its clock, again and again, until interrupted;
* :class:`DriveView` is the drive loop's observer (``dualarm-qp drive --foxglove``): it
  serves each sample as the loop records it.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

from ..control.trace import Trace
from ..errors import InvalidInputError
from .messages import CdrMessages, Message, message_definition
from .stream import Sample, StreamNames
from .topics import DEFAULT_PORT, HOST, TOPICS

if TYPE_CHECKING:
    from ..experiments.config import ExperimentConfig
    from ..experiments.setup import Experiment


class LiveView:
    """A Foxglove WebSocket server for the stream's topics (see the module).

    Parameters
    ----------
    store : rosbags Typestore
        The type store the messages were serialized with (their schemas).
    port : int
        The TCP port on 127.0.0.1 (0: any free one; :attr:`port` tells which).
    name : str
        The server's name, shown by the app.

    Raises
    ------
    InvalidInputError
        foxglove-sdk is not installed, or the port cannot be served.
    """

    def __init__(self, store: Any, *, port: int = DEFAULT_PORT, name: str = "dualarm_qp"
                 ) -> None:
        try:
            import foxglove
        except ImportError:
            raise InvalidInputError('a live view needs foxglove-sdk: pip install '
                                    '"dualarm-qp[foxglove]"') from None
        self._context = foxglove.Context()
        try:
            self._server = foxglove.start_server(name=name, host=HOST, port=port,
                                                 context=self._context)
        except Exception as err:  # the SDK's own error for a port in use
            raise InvalidInputError(f"cannot serve the live view on {HOST}:{port}: "
                                    f"{err}") from None
        self._channels = {
            topic: foxglove.Channel(topic, schema=foxglove.Schema(
                name=msgtype, encoding="ros2msg",
                data=message_definition(store, msgtype).encode()),
                message_encoding="cdr", context=self._context)
            for topic, msgtype in TOPICS.items()}
        self.port = int(self._server.port)

    @property
    def url(self) -> str:
        """The WebSocket address to connect to."""
        return f"ws://{HOST}:{self.port}"

    def subscribed(self, topic: str) -> bool:
        """Whether a client is subscribed to ``topic`` now."""
        return bool(self._channels[topic].has_sinks())

    def publish(self, message: Message) -> None:
        """Serve one message (to the clients subscribed to its topic)."""
        self._channels[message.topic].log(message.data, log_time=message.stamp_ns)

    def close(self) -> None:
        """Stop the server."""
        for channel in self._channels.values():
            channel.close()
        self._server.stop()


def replay(view: LiveView, messages: Sequence[Message], *, rate: float = 1.0,
           loops: int | None = None, sleep: Callable[[float], None] = time.sleep) -> int:
    """Serve ``messages`` at the pace of their stamps, ``loops`` times (None: until interrupted).

    Parameters
    ----------
    view : LiveView
        Where to serve them.
    messages : sequence of Message
        In time order.
    rate : float
        Stream time per wall time (2: twice as fast).
    loops : int, optional
        How many times to serve the whole run.
    sleep : callable
        How to wait [s] (tests may pass their own).

    Returns
    -------
    int
        The messages served.
    """
    if not rate > 0:
        raise InvalidInputError(f"the replay rate must be > 0, got {rate:g}")
    served = 0
    done = 0
    while loops is None or done < loops:
        if not messages:
            break
        t0 = messages[0].stamp_ns
        wall0 = time.monotonic()
        for msg in messages:
            wait = wall0 + (msg.stamp_ns - t0) * 1e-9 / rate - time.monotonic()
            if wait > 0:
                sleep(wait)
            view.publish(msg)
            served += 1
        done += 1
    return served


class DriveView:
    """The drive loop's observer that serves each recorded sample live.

    Parameters
    ----------
    view : LiveView
        Where to serve.
    messages : CdrMessages
        The task's messages.
    """

    def __init__(self, view: LiveView, messages: CdrMessages) -> None:
        self.view = view
        self.messages = messages

    def __call__(self, trace: Trace, k: int) -> None:
        """Serve row ``k`` of ``trace`` (just recorded)."""
        for msg in self.messages.sample(Sample.from_trace(trace, k)):
            self.view.publish(msg)


def open_drive_view(cfg: ExperimentConfig, exp: Experiment, path: str, *,
                    port: int = DEFAULT_PORT) -> DriveView:
    """Serve a drive of the experiment live (the joint names of its ``cell:`` section).

    Raises
    ------
    InvalidInputError
        foxglove-sdk or rosbags is missing, a joint list has the wrong length, or the
        port cannot be served.
    """
    names = StreamNames.of(exp.task, cfg.cell.leader.joints, cfg.cell.follower.joints,
                           path=path)
    messages = CdrMessages(exp.task, names)
    return DriveView(LiveView(messages.store, port=port), messages)


__all__ = ["DEFAULT_PORT", "HOST", "DriveView", "LiveView", "open_drive_view", "replay"]
