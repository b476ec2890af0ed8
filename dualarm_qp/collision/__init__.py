"""Collision avoidance: the scene (bodies and pairs), its settings, its clearance.

* :mod:`.settings`: :class:`CollisionSettings`, the velocity damper's distances;
* :mod:`.scene`: :class:`CollisionScene`, the bodies (links, object, obstacles), the
  pairs checked and their distances;
* :mod:`.clearance`: the clearance of a recorded motion.

The rows that keep the pairs apart are one limit of the step
(:mod:`dualarm_qp.step.limits.collision`).
"""

from .clearance import ClearanceHistory, ClearanceReport, clearance_history, clearance_report
from .scene import GROUPS, Body, CollisionScene, Measured, Pair
from .settings import CLEARANCE_ALLOWANCE, CollisionSettings

__all__ = ["CLEARANCE_ALLOWANCE", "GROUPS", "Body", "ClearanceHistory", "ClearanceReport",
           "CollisionScene", "CollisionSettings", "Measured", "Pair", "clearance_history",
           "clearance_report"]
