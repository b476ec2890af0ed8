"""Collision avoidance: the scene (bodies and pairs), its settings, its clearance.

* :mod:`.settings`: :class:`CollisionSettings`, the velocity damper's distances;
* :mod:`.scene`: :class:`CollisionScene`, the bodies (links, object, obstacles), the
  pairs checked and their distances;
* :mod:`.clearance`: the clearance of a recorded motion.

The rows that keep the pairs apart are one limit of the step
(:mod:`dualarm_qp.step.limits.collision`).

The settings are imported with the package; the scene's and the clearance's names
(the geometry, with Pinocchio and Coal) on first access: a run's figures read
:data:`CLEARANCE_ALLOWANCE` without loading the geometry.
"""

from typing import TYPE_CHECKING as _TYPE_CHECKING

from .._lazy import lazy_names as _lazy_names
from .settings import CLEARANCE_ALLOWANCE, CollisionSettings

if _TYPE_CHECKING:
    from .clearance import ClearanceHistory, ClearanceReport, clearance_history, clearance_report
    from .scene import GROUPS, Body, CollisionScene, Measured, Pair

#: Names imported on first access, and the module each comes from.
_LAZY = {
    "ClearanceHistory": "clearance",
    "ClearanceReport": "clearance",
    "clearance_history": "clearance",
    "clearance_report": "clearance",
    "GROUPS": "scene",
    "Body": "scene",
    "CollisionScene": "scene",
    "Measured": "scene",
    "Pair": "scene",
}

__all__ = ["CLEARANCE_ALLOWANCE", "GROUPS", "Body", "ClearanceHistory", "ClearanceReport",
           "CollisionScene", "CollisionSettings", "Measured", "Pair", "clearance_history",
           "clearance_report"]


#: Import a name of :data:`_LAZY` from its module on first access.
__getattr__ = _lazy_names(__name__, globals(), _LAZY)


def __dir__() -> list[str]:
    """List the public names, the lazy ones included."""
    return sorted(__all__)
