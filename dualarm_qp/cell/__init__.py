"""Cells: the controller on two arms, through one interface and one drive loop.

:mod:`.base` is the interface (:class:`~.base.Cell`), :mod:`.loop` the one loop that
drives every cell on the cell's own clock, :mod:`.safety` the clamp and the stop ramp,
:mod:`.grasp` the grasp estimated from both arms' joints. The back-ends: :mod:`.mujoco`
(the MuJoCo plant), :mod:`.ros2` (ros2_control's topics) and :mod:`.franka` (libfranka's
protocol through franky). ``docs/robots.md`` tells the whole story.

The names below are imported on first access, not with the package: the command line
adds ``drive`` and ``serve`` (:mod:`.command`, :mod:`.serve`) without loading a cell.
"""

from typing import TYPE_CHECKING as _TYPE_CHECKING

from .._lazy import lazy_names as _lazy_names

if _TYPE_CHECKING:
    from .base import Cell, CellError, CellSetupError, Reading
    from .grasp import GraspEstimate, estimate_grasp
    from .loop import DriveResult, DriveSettings, drive
    from .safety import CommandLimits, StopRamp, command_limits

#: Names imported on first access, and the module each comes from.
_LAZY = {
    "Cell": "base",
    "CellError": "base",
    "CellSetupError": "base",
    "Reading": "base",
    "GraspEstimate": "grasp",
    "estimate_grasp": "grasp",
    "DriveResult": "loop",
    "DriveSettings": "loop",
    "drive": "loop",
    "CommandLimits": "safety",
    "StopRamp": "safety",
    "command_limits": "safety",
}

__all__ = ["Cell", "CellError", "CellSetupError", "CommandLimits", "DriveResult",
           "DriveSettings", "GraspEstimate", "Reading", "StopRamp", "command_limits", "drive",
           "estimate_grasp"]


#: Import a name of :data:`_LAZY` from its module on first access.
__getattr__ = _lazy_names(__name__, globals(), _LAZY)


def __dir__() -> list[str]:
    """List the public names, the lazy ones included."""
    return sorted(__all__)
