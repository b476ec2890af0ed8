"""The task layer: surfaces, the sliding grasp path, Case 2 support and trajectories ``D(t)``.

Sits above the kinematics and below the step problem. Surfaces, support and
trajectories need no arm model; :mod:`.scene` ties them to the two arms.
"""

from .support import (
    SupportLine,
    SupportSolution,
    equilibrium_residual,
    gravity_tilde,
    support_line,
    support_point,
)
from .support_general import ImplicitSurface, solve_support, support_sliding_vector
from .surfaces import CenterLine, CurvedBar, CylinderSurface, GraspSurface, PlaneBar, case1_pose
from .trajectory import (
    PAPER_P0,
    PAPER_R0,
    PAPER_VELOCITY,
    LinearTrajectory,
    Trajectory,
    WaypointTrajectory,
    min_jerk,
    paper_trajectory,
)

__all__ = [
    "GraspSurface",
    "PlaneBar",
    "CylinderSurface",
    "CurvedBar",
    "CenterLine",
    "case1_pose",
    "ImplicitSurface",
    "SupportSolution",
    "SupportLine",
    "gravity_tilde",
    "equilibrium_residual",
    "support_point",
    "support_line",
    "solve_support",
    "support_sliding_vector",
    "Trajectory",
    "LinearTrajectory",
    "WaypointTrajectory",
    "paper_trajectory",
    "min_jerk",
    "PAPER_R0",
    "PAPER_P0",
    "PAPER_VELOCITY",
]
