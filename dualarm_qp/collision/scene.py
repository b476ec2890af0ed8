"""The collision scene: every body that can collide, and the pairs that are checked.

Bodies:

* each link of each arm: a capsule in the frame of the link (``arm.link_frames``),
  fitted to a URDF's collision geometry or laid along a DH table's links
  (:func:`~dualarm_qp.geometry.links.arm_capsules`); named ``leader.link3``,
  ``follower.base``, ...;
* the carried object: its shape in the object frame (``object``);
* the obstacles: shapes fixed in the world, by their names.

Pairs (:meth:`CollisionScene.build`):

* ``arm_arm``: every link of the leader against every link of the follower;
* ``arm_object``: each arm's links against the object, except the links of a grasping
  hand within ``grasp_clearance`` of its grasp point (they touch the object by design);
* ``obstacle``: the arms' links and the object against every obstacle;
* ``self``: an arm with more than six joints against itself, links at least
  :data:`SELF_GAP` joints apart;
* minus the pairs excluded by name, the pairs of two bodies no joint moves (an arm's
  base and an obstacle: their distance never changes), and the arm-arm, arm-object and
  self pairs that overlap at the start (which no limit could separate); each is reported
  as excluded, with its reason. An obstacle that overlaps an arm or the object at the
  start is an error (:class:`ObstacleOverlapError`): the scene is wrong.

Every body's pose is read from one stack of frames (:meth:`CollisionScene.frames`):
the leader's link frames, the follower's, the object frame and the world. Distances
come from :mod:`dualarm_qp.geometry.distance`: the closed form for capsule pairs (one
compiled call places the bodies, skips the far pairs and measures the others), and coal
for pairs with a box, measured in the same call (``src/kernel/coal_pairs.cpp``, with
coal's own C++ library). :meth:`measure` can skip
the pairs certainly farther apart than a given distance (the rows only need the pairs
within the influence distance): by their bounding spheres, then by their capsules, and
a pair with a box by the gaps between the box and the other body's capsule along the
box's axes, before coal is called.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._compiled import kernel
from .._remade import KernelHolder
from ..errors import InvalidInputError, NonFiniteError, ObstacleOverlapError
from ..geometry.bounds import bounding_capsule, distance_to_point
from ..geometry.distance import EPA_TOLERANCE, GJK_TOLERANCE, Proximities, coal_parts
from ..geometry.links import arm_capsules
from ..geometry.shapes import Box, Capsule
from ..kinematics.arm import SerialArm
from .settings import CollisionSettings

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]

#: The groups of pairs (``trajectory.csv`` has one clearance column per group).
GROUPS = ("arm_arm", "arm_object", "obstacle", "self")

#: Self-collision pairs of a redundant arm: links at least this many joints apart.
SELF_GAP = 3

#: Owners of bodies, in the order of the frame stack.
OWNERS = ("leader", "follower", "object", "world")


#: The reason recorded for a pair left out because it overlaps at the start.
OVERLAPPING_AT_START = "overlapping at the start"


@dataclass(frozen=True)
class Body:
    """One body of the scene.

    Attributes
    ----------
    name : str
        ``leader.link3``, ``follower.base``, ``object`` or an obstacle's name.
    owner : {"leader", "follower", "object", "world"}
        What carries it.
    link : int
        Index of its frame among the arm's ``link_frames`` (-1 for the object and the
        obstacles).
    shape : Capsule or Box
        The shape in the frame of its owner (its link, the object frame, the world).
    """

    name: str
    owner: str
    link: int
    shape: Capsule | Box


@dataclass(frozen=True)
class Pair:
    """Two bodies whose distance is checked (``a`` before ``b`` in the scene's bodies)."""

    a: int
    b: int
    group: str
    name: str


@dataclass(frozen=True, eq=False)
class Measured:
    """Proximities of some of the scene's pairs.

    Attributes
    ----------
    pairs : ndarray of int
        Indices of the measured pairs in :attr:`CollisionScene.pairs`.
    prox : Proximities
        Their signed distances, witness points and normals (from ``a`` to ``b``).
    """

    pairs: IntArray
    prox: Proximities


@dataclass
class CollisionScene(KernelHolder):
    """Bodies, pairs and settings of a task's collision avoidance.

    Attributes
    ----------
    bodies : list of Body
        The leader's links, the follower's, the object (if it has a shape), the
        obstacles.
    pairs : list of Pair
        The pairs checked.
    settings : CollisionSettings
        The damper's distances and whether the step keeps them.
    n_frames : tuple of int
        Link frames of the leader and of the follower (``n + 1`` each).
    excluded : list of (str, str)
        Pairs left out, with the reason.
    """

    _kernel_attributes = ("_exact",)  # made again when unpickled (_remake)

    bodies: list[Body]
    pairs: list[Pair]
    settings: CollisionSettings
    n_frames: tuple[int, int]
    excluded: list[tuple[str, str]] = field(default_factory=list)

    def __post_init__(self) -> None:
        n_l, n_f = self.n_frames
        start = {"leader": 0, "follower": n_l, "object": n_l + n_f, "world": n_l + n_f + 1}
        # What the kernel's measure reads (src/kernel/clearance.cpp): each body's frame in
        # the stack, its capsule, the pairs' bodies.
        self._frame_list = [start[b.owner] + max(b.link, 0) for b in self.bodies]
        # Every body as a capsule in its frame: its own, or one containing its box (the
        # box's longest axis, radius the half-diagonal of the other two): for a box the
        # closed form then gives a lower bound, the box's slabs against the other's
        # capsule a tighter one (a flat box's capsule is far too fat), and coal the
        # distance.
        bounds = [bounding_capsule(b.shape) for b in self.bodies]
        self._a = np.array([c[0] for c in bounds]).reshape(-1, 3)
        self._b = np.array([c[1] for c in bounds]).reshape(-1, 3)
        self._r = np.array([c[2] for c in bounds])
        self._sphere = 0.5 * np.linalg.norm(self._b - self._a, axis=1) + self._r
        self._ia_list = [p.a for p in self.pairs]
        self._ib_list = [p.b for p in self.pairs]
        boxed = [isinstance(b.shape, Box) for b in self.bodies]
        self._boxed = [boxed[p.a] or boxed[p.b] for p in self.pairs]
        self.group_of = np.array([GROUPS.index(p.group) for p in self.pairs], dtype=np.intp)
        self._remake()

    # -- names -------------------------------------------------------------------------
    @property
    def pair_names(self) -> list[str]:
        """Names of the pairs, in order (``leader.link3 - follower.link4``)."""
        return [p.name for p in self.pairs]

    @property
    def body_names(self) -> list[str]:
        """Names of the bodies, in order."""
        return [b.name for b in self.bodies]

    @property
    def obstacles(self) -> list[Body]:
        """The bodies fixed in the world."""
        return [b for b in self.bodies if b.owner == "world"]

    # -- placing and measuring -------------------------------------------------------------
    def frames(self, leader_frames: FloatArray, follower_frames: FloatArray,
               T_object: FloatArray) -> FloatArray:
        """Return the stack of frames the bodies are read from, shape (n_l + n_f + 4, 4, 4).

        Parameters
        ----------
        leader_frames, follower_frames : ndarray, shape (n + 1, 4, 4)
            World poses of each arm's link frames (``arm.link_frames(q)``) [m].
        T_object : ndarray, shape (4, 4)
            ``T_world_object`` [m].
        """
        return np.concatenate([leader_frames, follower_frames, T_object[None],
                               np.eye(4)[None]])

    def placed(self, frames: FloatArray) -> list[Capsule | Box]:
        """Every body in the world (its shape placed by its frame in ``frames``)."""
        out: list[Capsule | Box] = []
        for body, f in zip(self.bodies, self._frame_list, strict=True):
            out.append(body.shape.placed(frames[f]))
        return out

    def measure(self, frames: FloatArray, within: float = np.inf) -> Measured:
        """Signed distances, witness points and normals of the pairs, in the world.

        Parameters
        ----------
        frames : ndarray, shape (n_l + n_f + 4, 4, 4)
            The stack of :meth:`frames` [m].
        within : float
            Measure only the pairs that may be closer than this [m]: every pair closer
            is listed; the others may be, or are left out when certainly farther apart
            (their bounding spheres are, then their capsules; for a pair with a box,
            the gaps between the other body's capsule axis and the box along the box's
            three axes, less that capsule's radius); ``inf``: every pair.

        Returns
        -------
        Measured
            The measured pairs (in the order of :attr:`pairs`) and their proximities.

        Raises
        ------
        NonFiniteError
            A body's frame is not finite (its pairs are never skipped as far).
        """
        p = kernel.scene_proximities(
            np.ascontiguousarray(frames, dtype=np.float64).reshape(-1, 4), self._frame_list,
            self._a, self._b, self._r, self._sphere, self._ia_list, self._ib_list,
            float(within), self._exact)
        if not p.finite:
            raise NonFiniteError("the collision scene's frames")
        return Measured(p.pairs, Proximities(p.distance, p.point_a, p.point_b, p.normal))

    def measured_as(self) -> tuple[list[int], FloatArray, FloatArray, FloatArray, FloatArray,
                                   list[int], list[int], Any]:
        """Return the bodies and pairs as the kernel measures them (``scene_proximities``).

        The kernel's damper (``kernel.DamperScene``) reads the same.

        Returns
        -------
        body_frame : list of int
            Each body's frame in the stack of :meth:`frames`.
        a_local, b_local : ndarray, shape (n_bodies, 3)
            The ends of each body's capsule (a box's bounding capsule) in its frame [m].
        r : ndarray, shape (n_bodies,)
            Their radii [m].
        sphere : ndarray, shape (n_bodies,)
            The radius of each body's bounding sphere about its axis' midpoint [m].
        ia, ib : list of int
            The bodies of each pair.
        exact : kernel.CoalPairs or None
            The kernel's coal geometries and solvers of the pairs with a box (None when
            no pair has one).
        """
        return (self._frame_list, self._a, self._b, self._r, self._sphere, self._ia_list,
                self._ib_list, self._exact)

    def _remake(self) -> None:
        """Make the kernel's coal geometries and solvers of the pairs with a box (or None)."""
        self._exact: Any = None
        if any(self._boxed):
            parts = [coal_parts(b.shape) for b in self.bodies]
            self._exact = kernel.CoalPairs(
                [p[0] for p in parts], np.array([p[1] for p in parts]).reshape(-1, 3),
                np.concatenate([p[2] for p in parts]).reshape(-1, 4), self._ia_list,
                self._ib_list, self._boxed, GJK_TOLERANCE, EPA_TOLERANCE)

    def nearest(self, frames: FloatArray) -> tuple[FloatArray, list[str]]:
        """Smallest distance of each group [m] (``inf`` for an empty group) and its pair."""
        m = self.measure(frames)
        out = np.full(len(GROUPS), np.inf)
        names = [""] * len(GROUPS)
        for g in range(len(GROUPS)):
            idx = np.flatnonzero(self.group_of == g)
            if idx.size:
                j = int(idx[np.argmin(m.prox.distance[idx])])
                out[g] = m.prox.distance[j]
                names[g] = self.pairs[j].name
        return out, names

    # -- building -----------------------------------------------------------------------
    @classmethod
    def build(cls, leader: SerialArm, follower: SerialArm, *, settings: CollisionSettings,
              object_shape: Capsule | Box | None = None,
              obstacles: Sequence[tuple[str, Capsule | Box]] = (),
              leader_radii: FloatArray | None = None,
              follower_radii: FloatArray | None = None,
              exclude: Sequence[Sequence[str]] = (),
              start: tuple[FloatArray, FloatArray, FloatArray] | None = None
              ) -> CollisionScene:
        """Bodies and pairs of a task (see the module docstring).

        Parameters
        ----------
        leader, follower : SerialArm
            The arms (their links' capsules: :func:`~dualarm_qp.geometry.links.arm_capsules`).
        settings : CollisionSettings
            The damper's distances and the grasp clearance.
        object_shape : Capsule or Box, optional
            The object's shape in the object frame (None: the object is not checked).
        obstacles : sequence of (name, shape)
            Obstacles, their shapes in the world.
        leader_radii, follower_radii : ndarray, optional
            Capsule radii [m] of a DH arm's links (the PUMA preset has defaults).
        exclude : sequence of (str, str)
            Pairs never checked, by body names (``leader.link6``, ``object``, ...).
        start : (q_l, q_f, T_object), optional
            The joints [rad] and the object's pose [m] at the start: for the grasp
            clearance (measured from each arm's tool point) and for the pairs already
            overlapping, which are left out (reported in :attr:`excluded`).

        Raises
        ------
        InvalidInputError
            An excluded name that is no body of the scene, or two bodies of one name.
        """
        bodies: list[Body] = []
        for role, arm, radii in (("leader", leader, leader_radii),
                                 ("follower", follower, follower_radii)):
            names = arm.link_names
            for link, capsule in sorted(arm_capsules(arm, radii=radii).items()):
                bodies.append(Body(f"{role}.{names[link]}", role, link, capsule))
        if object_shape is not None:
            bodies.append(Body("object", "object", -1, object_shape))
        seen = {b.name for b in bodies}
        for name, shape in obstacles:
            if name in seen:
                raise InvalidInputError(f"obstacle name '{name}' is used twice or names a "
                                        "part of the arms or the object")
            seen.add(name)
            bodies.append(Body(name, "world", -1, shape))
        banned = set()
        for x, y in exclude:
            for name in (x, y):
                if name not in seen:
                    raise InvalidInputError(f"'{name}' is no body of the scene (bodies: "
                                            f"{', '.join(sorted(seen))})")
            banned.add(frozenset((x, y)))
        kept: list[Pair] = []
        excluded: list[tuple[str, str]] = []
        for i, a in enumerate(bodies):
            for j in range(i + 1, len(bodies)):
                b = bodies[j]
                group = _group(a, b, leader.n, follower.n)
                if group is None:
                    continue
                pair = Pair(i, j, group, f"{a.name} - {b.name}")
                if frozenset((a.name, b.name)) in banned:
                    excluded.append((pair.name, "excluded in the set-up"))
                elif _fixed(a) and _fixed(b):
                    excluded.append((pair.name, "neither body moves"))
                else:
                    kept.append(pair)
        scene = cls(bodies, kept, settings, (leader.n + 1, follower.n + 1), excluded)
        if start is not None:
            q_l, q_f, T_object = start
            frames = scene.frames(leader.link_frames(q_l), follower.link_frames(q_f),
                                  T_object)
            grasp = {"leader": leader.fk(q_l)[:3, 3], "follower": follower.fk(q_f)[:3, 3]}
            scene = scene._without_contact_at_start(frames, grasp)
        return scene

    def _without_contact_at_start(self, frames: FloatArray,
                                  grasp: dict[str, FloatArray]) -> CollisionScene:
        """Leave out the grasping hands' links near their grasp points, and overlapping pairs.

        Pairs that overlap at the start are left out: no limit could separate them.
        """
        placed = self.placed(frames)
        prox = self.measure(frames).prox
        kept, excluded = [], list(self.excluded)
        for i, pair in enumerate(self.pairs):
            a, b = self.bodies[pair.a], self.bodies[pair.b]
            if pair.group == "arm_object":
                arm, k = (a, pair.a) if a.owner in grasp else (b, pair.b)
                near = distance_to_point(placed[k], grasp[arm.owner])
                if near <= self.settings.grasp_clearance:
                    excluded.append((pair.name, f"the grasping hand ({near * 1e3:.0f} mm from "
                                                "its grasp point)"))
                    continue
            if prox.distance[i] < 0.0:
                if pair.group == "obstacle":  # the scene is wrong, not the arms' capsules
                    obstacle = a if a.owner == "world" else b
                    raise ObstacleOverlapError(
                        f"obstacle '{obstacle.name}' overlaps "
                        f"{(b if obstacle is a else a).name} at the start "
                        f"({-prox.distance[i] * 1e3:.1f} mm deep): move it or the arms",
                        obstacle.name)
                excluded.append((pair.name, f"{OVERLAPPING_AT_START} "
                                            f"({prox.distance[i] * 1e3:.1f} mm)"))
                continue
            kept.append(pair)
        return CollisionScene(self.bodies, kept, self.settings, self.n_frames, excluded)

    def overlapping_at_start(self) -> list[str]:
        """Names of the pairs left out because their shapes overlap at the start."""
        return [pair for pair, why in self.excluded if why.startswith(OVERLAPPING_AT_START)]

    def subset(self, pairs: Sequence[int]) -> CollisionScene:
        """Return the scene with only the given pairs (indices into :attr:`pairs`)."""
        return CollisionScene(self.bodies, [self.pairs[i] for i in pairs], self.settings,
                              self.n_frames, list(self.excluded))

    def summary(self) -> dict[str, object]:
        """JSON-ready: the settings, the pairs checked and the ones left out."""
        return {**self.settings.summary(), "pairs": self.pair_names,
                "excluded": [{"pair": p, "why": why} for p, why in self.excluded]}


def _group(a: Body, b: Body, n_l: int, n_f: int) -> str | None:
    """Return the group of a pair of bodies, or None when the pair is not checked."""
    owners = {a.owner, b.owner}
    if owners == {"leader", "follower"}:
        return "arm_arm"
    if "object" in owners and owners & {"leader", "follower"}:
        return "arm_object"
    if "world" in owners and owners != {"world"}:
        return "obstacle"
    if a.owner == b.owner and a.owner in ("leader", "follower"):
        n = n_l if a.owner == "leader" else n_f
        if n > 6 and abs(a.link - b.link) >= SELF_GAP:
            return "self"
    return None


def _fixed(body: Body) -> bool:
    """Whether no joint moves ``body`` (an obstacle, or an arm's base)."""
    return body.owner == "world" or (body.owner in ("leader", "follower") and body.link == 0)


__all__ = ["GROUPS", "Body", "CollisionScene", "Measured", "ObstacleOverlapError", "Pair"]
