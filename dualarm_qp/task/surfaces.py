"""Object surfaces and the follower's sliding grasp path (paper Section 2, Eqs. 3-6, 16, 21).

The follower's hand touches the object on the surface ``phi(r) = 0`` (Eq. 3, object
coordinates) and slides along a one-dimensional path on it. The path is parametrised by
a scalar ``sigma`` [m], the arc length along the sliding direction, so that

* ``point(sigma)`` is the contact point ``r2`` in object coordinates [m],
* ``tangent(sigma) = d point / d sigma`` is the unit sliding vector ``s*`` (Eq. 4),
* ``frame(sigma) = R2 = [s*, n*, a*]`` (Eqs. 16 and 21) with ``a* = grad phi / |grad phi|``
  (Eq. 5) and ``n* = a* x s*`` (Eq. 6), a proper rotation from the follower-hand frame to
  the object frame,
* ``angular_rate(sigma) = kappa`` with ``dR2/dsigma = skew(kappa) @ R2`` [rad/m], in
  object coordinates. While the hand slides at speed ``m = d sigma/dt`` [m/s] the hand
  frame turns at ``kappa * m`` [rad/s] relative to the object.

All methods accept any finite ``sigma``, also outside ``[sigma_min, sigma_max]``: the
geometry is extended naturally (a line, a generator line, a circle) so that a state that
starts outside the grasp range (as in the paper's Table 2, ``r2_z = 450 mm`` against
``r_max = 400 mm``) can still be evaluated; the range is a bound for the solvers, not a
domain restriction.

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
