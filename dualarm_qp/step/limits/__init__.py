"""The step's limits, one module each, stacked in registration order.

Importing this package registers every standard limit (:mod:`.ranges`,
:mod:`.speeds`, :mod:`.acceleration`, :mod:`.jerk`, :mod:`.collision`,
:mod:`.torque`); a new limit
is one module that defines the limit and registers its factory
(:func:`~.registry.register_limit`), plus one import line here.
"""

from . import acceleration, collision, jerk, ranges, speeds, torque  # noqa: F401  (registration)
from .acceleration import AccelerationLimit, braking_bound
from .collision import CollisionLimit
from .jerk import JerkLimit
from .ranges import RangeLimit
from .registry import LimitSetup, register_limit, registered_limits, standard_limits
from .speeds import SpeedLimit
from .torque import TorqueLimit

__all__ = ["AccelerationLimit", "CollisionLimit", "JerkLimit", "LimitSetup",
           "RangeLimit", "SpeedLimit",
           "TorqueLimit", "braking_bound", "register_limit", "registered_limits", "standard_limits"]
