"""What the 3D view draws of a task's collision scene: obstacles, shapes, the nearest pair.

A task with geometry carries a :class:`~dualarm_qp.collision.scene.CollisionScene`
(``task.scene``). The view draws from it:

- the **obstacles** (bodies owned by the world), fixed in the world, always shown;
- the **collision shapes** of the arms' links and of the object, each hung on the node
  of the view that carries it (:mod:`.scene`): a link's capsule on node ``link`` of its
  arm (node ``k`` is the arm's frame ``k``, the frame the scene places the capsule in),
  the object's shape on the object node. A shape's pose in its node is constant, so the
  shapes move with the samples' node poses alone; the page shows them on a toggle (off
  at first);
- per sample, the **nearest pair** while it is closer than the influence distance
  ``d_i`` (:func:`nearest_pair`): a segment between its witness points, labelled with
  the pair and its distance. It is measured here, in Python, with the scene's own
  :meth:`~dualarm_qp.collision.scene.CollisionScene.measure`, when the samples are
  packed (:mod:`.frames`).

Shapes are described as plain numbers: a capsule by its two endpoints and radius in its
node's frame (a sphere has both endpoints at its centre), a box by its edge lengths and
its column-major pose in its node's frame [m].
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..collision.scene import CollisionScene
from ..geometry.shapes import Box, Capsule

FloatArray = NDArray[np.float64]

#: Colours of the obstacles, of the links' and the object's collision shapes (drawn
#: translucent) and of the nearest pair's segment (``#rrggbb``).
COLLISION_COLOURS = {"obstacle": "#8c564b", "shape": "#17becf", "nearest": "#e6007e"}

#: Opacity of the collision shapes of the links and the object.
SHAPE_OPACITY = 0.35

#: The nearest pair's segment: its radius and that of the balls at its ends [m].
NEAREST_RADIUS, WITNESS_RADIUS = 0.005, 0.009


def shape_part(shape: Capsule | Box) -> dict[str, Any]:
    """Describe a collision shape in its frame, JSON-ready [m].

    Returns
    -------
    dict
        ``{"shape": "capsule", "a", "b", "radius"}`` (a sphere when ``a == b``) or
        ``{"shape": "box", "size", "pose"}`` with ``pose`` column-major (three.js
        ``Matrix4.fromArray``).
    """
    if isinstance(shape, Capsule):
        return {"shape": "capsule", "a": _rounded(shape.a), "b": _rounded(shape.b),
                "radius": round(float(shape.radius), 7)}
    return {"shape": "box", "size": _rounded(shape.size), "pose": _rounded(shape.pose.T.ravel())}


def _rounded(values: Any) -> list[float]:
    return [round(float(x), 7) for x in np.asarray(values, dtype=float).ravel()]


def collision_parts(scene: CollisionScene | None) -> dict[str, Any] | None:
    """Describe what the view draws of a collision scene; None without a scene.

    Parameters
    ----------
    scene : CollisionScene or None
        The task's scene (``task.scene``).

    Returns
    -------
    dict or None
        ``obstacles`` (``name`` and ``part``, in world coordinates), ``shapes`` (the
        links' and the object's: ``name``, ``owner`` (``"leader"``, ``"follower"`` or
        ``"object"``), ``node`` (the node of that arm, 0 for the object) and ``part``),
        ``pairs`` (the names of the pairs checked: a sample's nearest pair indexes
        them), ``influence_distance`` and ``safety_distance`` [m], ``enabled``
        (whether the step kept the pairs apart), ``colours`` and ``shape_opacity``.
    """
    if scene is None:
        return None
    obstacles, shapes = [], []
    for body in scene.bodies:
        part = shape_part(body.shape)
        if body.owner == "world":
            obstacles.append({"name": body.name, "part": part})
        else:
            shapes.append({"name": body.name, "owner": body.owner,
                           "node": max(body.link, 0), "part": part})
    s = scene.settings
    return {"obstacles": obstacles, "shapes": shapes, "pairs": scene.pair_names,
            "influence_distance": s.influence_distance, "safety_distance": s.safety_distance,
            "enabled": s.enabled, "colours": dict(COLLISION_COLOURS),
            "shape_opacity": SHAPE_OPACITY, "nearest_radius": NEAREST_RADIUS,
            "witness_radius": WITNESS_RADIUS}


@dataclass(frozen=True)
class NearestPair:
    """The nearest pair of one sample, closer than the influence distance.

    Attributes
    ----------
    pair : int
        Its index in the scene's pairs (:attr:`~dualarm_qp.collision.scene.
        CollisionScene.pairs`).
    name : str
        Its name (``follower.link2 - pillar``).
    distance : float
        Signed distance [m] (negative: the shapes overlap).
    point_a, point_b : ndarray, shape (3,)
        Witness points on its two bodies, in the world [m].
    """

    pair: int
    name: str
    distance: float
    point_a: FloatArray
    point_b: FloatArray


def nearest_pair(scene: CollisionScene, frames: FloatArray) -> NearestPair | None:
    """Return the nearest pair at one placement if it is closer than ``d_i``, else None.

    Parameters
    ----------
    scene : CollisionScene
        The task's scene.
    frames : ndarray, shape (n_l + n_f + 4, 4, 4)
        Its stack of frames (:meth:`~dualarm_qp.collision.scene.CollisionScene.frames`)
        [m].
    """
    d_i = scene.settings.influence_distance
    measured = scene.measure(frames, within=d_i)
    if measured.pairs.size == 0:
        return None
    j = int(np.argmin(measured.prox.distance))
    distance = float(measured.prox.distance[j])
    if not distance < d_i:
        return None
    pair = int(measured.pairs[j])
    return NearestPair(pair, scene.pairs[pair].name, distance,
                       np.array(measured.prox.point_a[j]), np.array(measured.prox.point_b[j]))


__all__ = ["COLLISION_COLOURS", "NearestPair", "collision_parts", "nearest_pair", "shape_part"]
