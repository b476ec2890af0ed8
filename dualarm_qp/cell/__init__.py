"""Cells: the controller on two arms, through one interface and one drive loop.

:mod:`.base` is the interface (:class:`~.base.Cell`), :mod:`.loop` the one loop that
drives every cell on the cell's own clock, :mod:`.safety` the clamp and the stop ramp,
:mod:`.grasp` the grasp estimated from both arms' joints. The back-ends: :mod:`.mujoco`
(the MuJoCo plant), :mod:`.ros2` (ros2_control's topics) and :mod:`.franka` (libfranka's
protocol through franky). ``docs/robots.md`` tells the whole story.
"""

from .base import Cell, CellError, CellSetupError, Reading
from .grasp import GraspEstimate, estimate_grasp
from .loop import DriveResult, DriveSettings, drive
from .safety import CommandLimits, StopRamp, command_limits

__all__ = ["Cell", "CellError", "CellSetupError", "CommandLimits", "DriveResult",
           "DriveSettings", "GraspEstimate", "Reading", "StopRamp", "command_limits", "drive",
           "estimate_grasp"]
