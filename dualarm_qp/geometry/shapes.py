"""Collision shapes: capsules (spheres are capsules of zero length) and boxes.

Each shape is given in a *local* frame: the frame of the link that carries it (for an
arm, the frame of the joint that moves the link), or the world for a fixed obstacle.
:meth:`Capsule.placed` and :meth:`Box.placed` take the pose of that frame in the world,
``T_world_frame`` (4x4), and return the same kind of shape with its data in the world
frame; distances (:mod:`dualarm_qp.geometry.distance`) are computed between shapes
placed in one common frame.

A sphere is a capsule whose two endpoints coincide (:func:`sphere` builds one): the
distance code then has one closed form for every capsule-capsule, capsule-sphere and
sphere-sphere pair, and one compiled call for many pairs at once.

Units are SI: lengths in metres.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._validate import as_array, as_pose
from ..errors import InvalidInputError
from ..kinematics.arm import checked_pose

FloatArray = NDArray[np.float64]


def _frozen(value: FloatArray) -> FloatArray:
    """Return a read-only float64 copy of ``value``."""
    arr = np.array(value, dtype=np.float64)
    arr.flags.writeable = False
    return arr


@dataclass(frozen=True, eq=False)
class Capsule:
    """A capsule: every point within ``radius`` of the segment from ``a`` to ``b``.

    Parameters
    ----------
    a, b : array_like, shape (3,)
        Endpoints of the axis segment in the shape's frame [m]. ``a == b`` makes a
        sphere of centre ``a``.
    radius : float
        Radius [m], positive.

    Raises
    ------
    ShapeError, NonFiniteError
        An endpoint is not a finite 3-vector.
    InvalidInputError
        The radius is not a finite positive number.
    """

    a: FloatArray
    b: FloatArray
    radius: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "a", _frozen(as_array(self.a, "capsule endpoint a", (3,))))
        object.__setattr__(self, "b", _frozen(as_array(self.b, "capsule endpoint b", (3,))))
        object.__setattr__(self, "radius", _positive(self.radius, "capsule radius"))

    @property
    def length(self) -> float:
        """Length of the axis segment [m] (0 for a sphere)."""
        return float(np.linalg.norm(self.b - self.a))

    @property
    def is_sphere(self) -> bool:
        """Whether the two endpoints coincide (the capsule is a sphere)."""
        return bool(np.array_equal(self.a, self.b))

    def placed(self, T_world_frame: Any) -> Capsule:
        """Return the capsule in the world, its frame being at ``T_world_frame``.

        Parameters
        ----------
        T_world_frame : array_like, shape (4, 4)
            Pose of the capsule's frame in the world [m].

        Returns
        -------
        Capsule
            Endpoints in the world frame [m], same radius.

        Raises
        ------
        ShapeError, NonFiniteError, InvalidInputError
            ``T_world_frame`` is not a rigid transform.
        """
        T = checked_pose(T_world_frame, "T_world_frame")
        R, p = T[:3, :3], T[:3, 3]
        return Capsule(R @ self.a + p, R @ self.b + p, self.radius)

    def __repr__(self) -> str:
        return (f"Capsule(a={self.a.tolist()}, b={self.b.tolist()}, "
                f"radius={self.radius!r})")


@dataclass(frozen=True, eq=False)
class Box:
    """A rectangular box (cuboid).

    Parameters
    ----------
    size : array_like, shape (3,)
        Full edge lengths along the box's own x, y and z axes [m], each positive.
    pose : array_like, shape (4, 4), optional
        Pose of the box's centre and axes in the shape's frame [m]; identity by
        default (the box centred on the frame's origin, aligned with its axes).

    Raises
    ------
    ShapeError, NonFiniteError
        ``size`` is not a finite 3-vector or ``pose`` not a finite 4x4 array.
    InvalidInputError
        An edge length is not positive, or ``pose`` is not a rigid transform.
    """

    size: FloatArray
    pose: FloatArray = field(default_factory=lambda: np.eye(4))

    def __post_init__(self) -> None:
        size = as_array(self.size, "box size", (3,))
        if not (size > 0.0).all():
            raise InvalidInputError(f"box size must be positive edge lengths [m], "
                                    f"got {size.tolist()}")
        object.__setattr__(self, "size", _frozen(size))
        object.__setattr__(self, "pose", _frozen(as_pose(self.pose, "box pose")))

    @property
    def centre(self) -> FloatArray:
        """Centre of the box in the shape's frame [m], shape (3,)."""
        return self.pose[:3, 3]

    @property
    def half_size(self) -> FloatArray:
        """Half edge lengths [m], shape (3,)."""
        return self.size / 2.0

    def placed(self, T_world_frame: Any) -> Box:
        """Return the box in the world, its frame being at ``T_world_frame``.

        Parameters
        ----------
        T_world_frame : array_like, shape (4, 4)
            Pose of the box's frame in the world [m].

        Returns
        -------
        Box
            Same size; ``pose`` is the box's pose in the world,
            ``T_world_frame @ pose``.

        Raises
        ------
        ShapeError, NonFiniteError, InvalidInputError
            ``T_world_frame`` is not a rigid transform.
        """
        return Box(self.size, checked_pose(T_world_frame, "T_world_frame") @ self.pose)

    def __repr__(self) -> str:
        return f"Box(size={self.size.tolist()}, pose={self.pose.tolist()})"


#: A collision shape of this package.
Shape = Capsule | Box


def sphere(radius: float, centre: Any = (0.0, 0.0, 0.0)) -> Capsule:
    """Build a sphere: a capsule whose endpoints are both ``centre``.

    Parameters
    ----------
    radius : float
        Radius [m], positive.
    centre : array_like, shape (3,)
        Centre in the shape's frame [m]; the frame's origin by default.

    Returns
    -------
    Capsule
        ``Capsule(centre, centre, radius)``.
    """
    c = as_array(centre, "sphere centre", (3,))
    return Capsule(c, c, radius)


def transform_points(T: Any, points: Any) -> FloatArray:
    """Apply poses to points, one pose per point (vectorised, no validation).

    Parameters
    ----------
    T : ndarray, shape (k, 4, 4)
        Poses ``T_world_frame`` [m], e.g. rows of ``SerialArm.link_frames(q)``.
    points : ndarray, shape (k, 3)
        Points in their frames [m].

    Returns
    -------
    ndarray, shape (k, 3)
        ``R_i p_i + t_i`` in the world [m].
    """
    T = np.asarray(T, dtype=np.float64)
    p = np.asarray(points, dtype=np.float64)
    out: FloatArray = np.einsum("kij,kj->ki", T[:, :3, :3], p) + T[:, :3, 3]
    return out


def _positive(value: Any, name: str) -> float:
    """``value`` as a finite positive float, or :class:`InvalidInputError`."""
    try:
        x = float(value)
    except (TypeError, ValueError) as err:
        raise InvalidInputError(f"{name} must be a number [m], got {value!r}") from err
    except OverflowError as err:  # an integer beyond the largest float
        raise InvalidInputError(f"{name} must be finite and positive [m], got an integer "
                                "beyond the largest float") from err
    if not np.isfinite(x) or x <= 0.0:
        raise InvalidInputError(f"{name} must be finite and positive [m], got {x!r}")
    return x
