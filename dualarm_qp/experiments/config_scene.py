"""The scene of an experiment file: the object's shape, obstacles and collision settings.

::

    object:
      shape: {box: {size: [40, 40, 700]}, pose: {position: [0, 0, 350]}}
    scene:
      obstacles:
        - {name: pillar, capsule: {radius: 60, length: 1200}, pose: {position: [...]}}
        - {name: shelf, box: {size: [...]}, pose: {...}}
        - {name: lamp, sphere: {radius: 50}, pose: {position: [...]}}
    collision:
      enabled: true
      influence_distance: 100      # d_i (length unit)
      safety_distance: 20          # d_s
      approach_speed_max: 200      # xi (length unit per time unit)
      grasp_clearance: 150         # the grasping hands' links this near their grasp
      exclude: [[leader.link6, object], [follower.link3, pillar]]

Lengths are in the file's length unit, angles in its angle unit; converted to SI by the
experiment's setup. A capsule lies along its own z axis, centred on its pose; a box is
centred on its pose.
"""

from __future__ import annotations

from typing import Annotated

from pydantic import Field, model_validator

from .config_types import Flag, Model, Num, PoseSpec, Vec3, keyed


class CapsuleSize(Model):
    """A capsule: ``radius`` and the ``length`` of its axis (length unit)."""

    radius: Num
    length: Num = 0.0

    @model_validator(mode="after")
    def _positive(self) -> CapsuleSize:
        if not self.radius > 0:
            raise keyed("radius", f"must be > 0 (got {self.radius:g})")
        if self.length < 0:
            raise keyed("length", f"must be >= 0 (got {self.length:g})")
        return self


class SphereSize(Model):
    """A sphere: its ``radius`` (length unit)."""

    radius: Num

    @model_validator(mode="after")
    def _positive(self) -> SphereSize:
        if not self.radius > 0:
            raise keyed("radius", f"must be > 0 (got {self.radius:g})")
        return self


class BoxSize(Model):
    """A box: its edge lengths ``size: [x, y, z]`` (length unit)."""

    size: Vec3

    @model_validator(mode="after")
    def _positive(self) -> BoxSize:
        if not all(v > 0 for v in self.size):
            raise keyed("size", f"every edge must be > 0 (got {self.size})")
        return self


class ShapeSpec(Model):
    """One shape: exactly one of ``box``, ``capsule`` or ``sphere``, and its ``pose``."""

    box: BoxSize | None = None
    capsule: CapsuleSize | None = None
    sphere: SphereSize | None = None
    pose: PoseSpec = Field(default_factory=PoseSpec)

    @model_validator(mode="after")
    def _one(self) -> ShapeSpec:
        given = [k for k in ("box", "capsule", "sphere") if getattr(self, k) is not None]
        if len(given) != 1:
            raise keyed("box", "give exactly one of 'box', 'capsule' or 'sphere'"
                        + (f" (got {', '.join(given)})" if given else ""))
        return self


class ObstacleSpec(ShapeSpec):
    """A fixed obstacle of the scene: a ``name`` and a shape in the world frame."""

    name: Annotated[str, Field(min_length=1, max_length=100)]


class SceneSpec(Model):
    """What stands in the arms' way: ``obstacles``, each named once."""

    obstacles: Annotated[list[ObstacleSpec], Field(max_length=1000)] = Field(
        default_factory=list)

    @model_validator(mode="after")
    def _names(self) -> SceneSpec:
        seen: set[str] = set()
        for i, obstacle in enumerate(self.obstacles):
            if obstacle.name in seen:
                raise keyed(f"obstacles.{i}.name", f"'{obstacle.name}' names two obstacles")
            if obstacle.name in ("object",) or obstacle.name.startswith(("leader.",
                                                                       "follower.")):
                raise keyed(f"obstacles.{i}.name", f"'{obstacle.name}' is the name of a part "
                            "of the arms or of the object")
            seen.add(obstacle.name)
        return self


class CollisionSpec(Model):
    """Collision avoidance as hard limits (the velocity damper).

    For each pair of shapes closer than ``influence_distance`` (``d_i``), the distance
    may shrink at most at ``approach_speed_max (d - d_s) / (d_i - d_s)`` (``xi``,
    length unit per time unit), so that it never falls below ``safety_distance``
    (``d_s``). ``grasp_clearance``: the links of a grasping hand within this distance of
    its grasp point are not paired with the object. ``exclude``: pairs that are never
    checked, by name (``leader.<link>``, ``follower.<link>``, ``object`` or an
    obstacle's name).
    """

    enabled: Flag = False
    influence_distance: Num = 100.0
    safety_distance: Num = 20.0
    approach_speed_max: Num = 200.0
    grasp_clearance: Num = 150.0
    exclude: Annotated[list[Annotated[list[Annotated[str, Field(min_length=1)]],
                                      Field(min_length=2, max_length=2)]],
                       Field(max_length=10_000)] = Field(default_factory=list)

    @model_validator(mode="after")
    def _distances(self) -> CollisionSpec:
        if not self.safety_distance >= 0:
            raise keyed("safety_distance", f"must be >= 0 (got {self.safety_distance:g})")
        if not self.influence_distance > self.safety_distance:
            raise keyed("influence_distance", f"must be larger than safety_distance "
                        f"({self.influence_distance:g} <= {self.safety_distance:g})")
        if not self.approach_speed_max > 0:
            raise keyed("approach_speed_max", f"must be > 0 (got {self.approach_speed_max:g})")
        if not self.grasp_clearance >= 0:
            raise keyed("grasp_clearance", f"must be >= 0 (got {self.grasp_clearance:g})")
        return self


__all__ = ["BoxSize", "CapsuleSize", "CollisionSpec", "ObstacleSpec", "SceneSpec",
           "ShapeSpec", "SphereSize"]
