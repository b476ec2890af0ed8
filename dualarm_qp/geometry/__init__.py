"""Collision geometry: shapes, their signed distances, and capsules fitted to arms.

* :mod:`~dualarm_qp.geometry.shapes`: :class:`Capsule` (a sphere is a capsule of zero
  length, :func:`sphere`) and :class:`Box`, each in a local frame, placed in the world
  by ``placed(T_world_frame)``.
* :mod:`~dualarm_qp.geometry.distance`: :func:`proximity` (any pair) and
  :func:`capsule_proximities` (many capsule pairs at once): signed distance, witness
  points and the unit normal from a to b.
* :mod:`~dualarm_qp.geometry.fit`: :func:`fit_capsule`, a capsule containing points or
  balls, and :func:`geometry_balls` for coal meshes and primitives.
* :mod:`~dualarm_qp.geometry.links`: the capsules of an arm, keyed like
  ``SerialArm.link_frames``: :func:`arm_capsules`, :func:`urdf_capsules`,
  :func:`example_robot_capsules`, :func:`dh_capsules`.
* :mod:`~dualarm_qp.geometry.capsule_cache`: a URDF arm's fitted capsules kept on disk
  (``$DUALARM_QP_CACHE``, else the user's cache folder), keyed by the geometry fitted.
"""

from .distance import (
    TOUCH_TOL,
    Proximities,
    Proximity,
    capsule_proximities,
    proximity,
    segment_closest_points,
)
from .fit import fit_capsule, geometry_balls
from .links import (
    PUMA560_LINK_RADII,
    arm_capsules,
    dh_capsules,
    example_robot_capsules,
    urdf_capsules,
)
from .shapes import Box, Capsule, Shape, sphere, transform_points

__all__ = [
    "PUMA560_LINK_RADII",
    "TOUCH_TOL",
    "Box",
    "Capsule",
    "Proximities",
    "Proximity",
    "Shape",
    "arm_capsules",
    "capsule_proximities",
    "dh_capsules",
    "example_robot_capsules",
    "fit_capsule",
    "geometry_balls",
    "proximity",
    "segment_closest_points",
    "sphere",
    "transform_points",
    "urdf_capsules",
]
