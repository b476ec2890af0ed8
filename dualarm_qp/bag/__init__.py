"""A run as ROS 2 messages: a rosbag2 (MCAP) of it, and a live view of the same stream.

:mod:`.stream` gives each recorded sample's joints (with the grasp as a virtual joint),
frames (the object, ``D(t)``, the grasp point) and status; :mod:`.messages` serializes
them as ROS 2 does, without ROS (rosbags); :mod:`.write` writes a run folder as a bag
(``dualarm-qp bag``). ``docs/robots.md`` ("Bags and live views") tells the whole story.

The names below are imported on first access, not with the package: the command line
adds ``bag`` (:mod:`.command`) without loading the stream.
"""

from typing import TYPE_CHECKING as _TYPE_CHECKING

from .._lazy import lazy_names as _lazy_names

if _TYPE_CHECKING:
    from .stream import Frames, Sample, StreamNames, diagnostic_level, frames

#: Names imported on first access, and the module each comes from.
_LAZY = {
    "Frames": "stream",
    "Sample": "stream",
    "StreamNames": "stream",
    "diagnostic_level": "stream",
    "frames": "stream",
}

__all__ = ["Frames", "Sample", "StreamNames", "diagnostic_level", "frames"]


#: Import a name of :data:`_LAZY` from its module on first access.
__getattr__ = _lazy_names(__name__, globals(), _LAZY)


def __dir__() -> list[str]:
    """List the public names, the lazy ones included."""
    return sorted(__all__)
