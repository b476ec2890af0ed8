"""A run as ROS 2 messages: a rosbag2 (MCAP) of it, and a live view of the same stream.

:mod:`.stream` gives each recorded sample's joints (with the grasp as a virtual joint),
frames (the object, ``D(t)``, the grasp point) and status; :mod:`.messages` serializes
them as ROS 2 does, without ROS (rosbags); :mod:`.write` writes a run folder as a bag
(``dualarm-qp bag``). ``docs/robots.md`` ("Bags and live views") tells the whole story.
"""

from .stream import Frames, Sample, StreamNames, diagnostic_level, frames

__all__ = ["Frames", "Sample", "StreamNames", "diagnostic_level", "frames"]
