"""The follower's sliding grasp paths, all in one place (paper Section 2, Eqs. 3-6, 16, 21).

A path is parametrised by its arc length ``sigma`` [m] and gives the contact point, the
sliding vector ``s*``, the hand frame ``R2`` and its turning rate: the parametrisation
and its conventions are stated once, in :mod:`.surface_base`.

The base class is in :mod:`.surface_base`, each concrete path in a module of its own;
this module imports them all. Concrete paths: :class:`PlaneBar` (the paper's Fig. 4
bar, and any straight path on a plane), :class:`CylinderSurface` (a generator line of
a circular cylinder) and :class:`CurvedBar` (a bar bent into a circular arc, where
``s*`` really changes).
:func:`case1_pose` is the paper's Case 1 construction (Steps 1-4) from a surface and a
centre line ``x(z), y(z)``.
"""

from .case1 import CenterLine, case1_pose
from .curved_bar import CurvedBar
from .cylinder import CylinderSurface
from .plane_bar import PlaneBar
from .surface_base import GraspSurface, SlideJoint

__all__ = [
    "GraspSurface",
    "SlideJoint",
    "PlaneBar",
    "CylinderSurface",
    "CurvedBar",
    "CenterLine",
    "case1_pose",
]
