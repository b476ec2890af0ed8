"""The load each hand carries: the statics of the carried object (paper Eqs. 7-13, extended).

The object is at rest (quasi-static: the plan's accelerations are not counted). Gravity
pulls its mass ``M`` [kg] at its mass centre; the two hands hold it. Every vector here is
in the world frame; a *wrench* is ``w = [f; m]``, the force [N] and the moment [N m]
that a hand applies **to the object**, the moment taken **about that hand's grasp
point** (the origin of its grasp frame: the leader's tool point, the follower's contact
point ``r2``). A *twist* ``t = [v; omega]`` is the velocity of that point and the angular
velocity; ``w . t`` is power.

What each hand can transmit (its *wrench space*) follows from how it holds the object:

* a **rigid grasp** (the leader's ``H1``, Eq. 14) transmits any wrench (6 dims);
* a **sliding grasp** (the follower's in Case 1, and a sliding leader grasp) is
  frictionless: the palm on ball bearings (the paper's Section 1) does no work on the
  motions it lets through. Those *free twists* are the slide along the path,
  ``[s*; kappa]`` per m of ``sigma`` (``kappa`` the frame's turn rate,
  :meth:`GraspSurface.angular_rate`, zero on a straight path), and the spin about the
  sliding axis, ``[0; s*]``. Its wrench space is their reciprocal, ``w . t = 0``: on a
  straight path **no force along** ``s*`` **and no moment about it**, 4 dims;
* a **support** (Case 2, Eq. 10) pushes along the surface normal only, ``f = h a*``,
  ``h > 0``, with ``h`` given by the paper's support line
  (:class:`~dualarm_qp.task.support.SupportLine`): a prescribed wrench, not a share to
  split.

Balance (Eqs. 7-8 with every force and moment kept, about any common point ``o``)::

    sum_i [f_i; m_i + (p_i - o) x f_i]  +  [M g; (p_c - o) x M g]  =  0.

With more wrench dimensions than the 6 equations (a rigid leader and a sliding follower:
10), the balance leaves an *internal* part that squeezes the object without moving it.
The **split rule**: the minimum-norm wrench pair,

    minimise  sum_i ( |f_i|^2 + |m_i|^2 / L^2 )   subject to the balance and the spaces,

with ``L`` [m] the distance between the two grasp points (1 m if they coincide). This is
the split with zero internal force in that metric: every other balancing split is it plus
an internal wrench orthogonal to it, so its norm is larger by exactly the internal
wrench's norm. ``L`` makes force and moment commensurable (a moment ``m`` at one hand
costs what the force couple ``m / L`` across the two grasps that could replace it
costs) and the split independent of the unit of length. docs/derivation.md, section
"The load each hand carries", derives it and states the checks.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._validate import as_array
from ..errors import InvalidInputError

FloatArray = NDArray[np.float64]

__all__ = [
    "BALANCE_RTOL",
    "GraspStatics",
    "LoadSplit",
    "ObjectLoad",
    "UnbalancedLoadError",
    "rigid_grasp",
    "sliding_grasp",
    "split_load",
    "support_push",
    "wrench_space",
]

#: Largest balance residual, relative to the weight ``M |g|`` (force rows) and to
#: ``M |g| L`` (moment rows), for a load the hands can hold.
BALANCE_RTOL = 1e-9

#: Length [m] that weighs moments when the two grasp points coincide.
FALLBACK_LENGTH = 1.0


class UnbalancedLoadError(InvalidInputError):
    """The hands' wrench spaces cannot balance the weight (the object would slide or turn)."""


@dataclass(frozen=True)
class ObjectLoad:
    """The carried object's mass, mass centre and gravity.

    Parameters
    ----------
    mass : float
        ``M`` [kg], finite and > 0.
    mass_centre : array_like, shape (3,)
        ``r_c`` [m], object coordinates.
    gravity : array_like, shape (3,)
        ``g`` [m/s^2], world frame, non-zero.

    Raises
    ------
    InvalidInputError
        A mass that is not finite and positive, a mass centre or gravity that is not 3
        finite numbers, or zero gravity.
    """

    mass: float
    mass_centre: FloatArray
    gravity: FloatArray

    def __post_init__(self) -> None:
        try:
            m = float(self.mass)
        except (TypeError, ValueError, OverflowError):
            m = math.nan
        if not (math.isfinite(m) and m > 0.0):
            raise InvalidInputError(f"mass must be a finite number > 0 kg, got {self.mass!r}")
        g = as_array(self.gravity, "gravity", (3,)).copy()
        if not float(np.linalg.norm(g)) > 0.0:
            raise InvalidInputError("gravity must be a non-zero vector [m/s^2]")
        object.__setattr__(self, "mass", m)
        object.__setattr__(self, "mass_centre",
                           as_array(self.mass_centre, "mass_centre", (3,)).copy())
        object.__setattr__(self, "gravity", g)

    @property
    def weight(self) -> float:
        """``M |g|`` [N]."""
        return self.mass * float(np.linalg.norm(self.gravity))


@dataclass(frozen=True)
class GraspStatics:
    """What one hand can transmit to the object, at one state (world frame).

    Build it with :func:`rigid_grasp`, :func:`sliding_grasp` or :func:`support_push`.

    Attributes
    ----------
    point : ndarray, shape (3,)
        The grasp point [m], about which the hand's moment is taken.
    free : ndarray, shape (6, k)
        The free twists ``[v; omega]`` of the grasp about ``point`` (k = 0: rigid).
    wrench : ndarray, shape (6,) or None
        A prescribed wrench ``[f; m]`` (a support's push); None: the hand's share is
        found by the split rule.
    """

    point: FloatArray
    free: FloatArray
    wrench: FloatArray | None = None


def rigid_grasp(point: Any) -> GraspStatics:
    """Return a rigid grasp at ``point`` [m]: any wrench (6 dims)."""
    return rigid_statics(as_array(point, "point", (3,)))


def rigid_statics(point: FloatArray) -> GraspStatics:
    """:func:`rigid_grasp` of a float64 (3,) ``point`` computed from checked values.

    What the per-step statics call (:func:`.hands.hand_statics`): the point comes from the
    leader's checked kinematics, so it is not checked again.
    """
    return GraspStatics(point.copy(), np.zeros((6, 0)))


def sliding_grasp(point: Any, sliding: Any, turn: Any = (0.0, 0.0, 0.0)) -> GraspStatics:
    """Return a frictionless sliding grasp at ``point`` [m]: 4 dims.

    Parameters
    ----------
    point : array_like, shape (3,)
        The contact point [m], world frame.
    sliding : array_like, shape (3,)
        The sliding direction ``s*`` (normalised here), world frame.
    turn : array_like, shape (3,)
        The hand frame's turn per m of slide, ``kappa`` [rad/m], world frame (zero on
        a straight path).

    Returns
    -------
    GraspStatics
        Free twists: the slide ``[s*; kappa]`` and the spin ``[0; s*]``.
    """
    return sliding_statics(as_array(point, "point", (3,)),
                           as_array(sliding, "sliding", (3,)), as_array(turn, "turn", (3,)))


def sliding_statics(point: FloatArray, sliding: FloatArray, turn: FloatArray) -> GraspStatics:
    """:func:`sliding_grasp` of float64 (3,) arrays computed from checked values.

    What the per-step statics call (:func:`.hands.hand_statics`, the torque rows): the hands'
    points and directions come from the arms' kinematics and the surfaces at a checked
    state, so they are not checked again (a step's rows are checked where the builder
    stacks them).

    Raises
    ------
    InvalidInputError
        ``sliding`` is zero.
    """
    n = math.sqrt(float(sliding.dot(sliding)))  # np.linalg.norm's own sum, without its call
    if not n > 0.0:
        raise InvalidInputError("sliding must be a non-zero vector")
    s = sliding / n
    free = np.zeros((6, 2))
    free[:3, 0] = s
    free[3:, 0] = turn
    free[3:, 1] = s
    return GraspStatics(point.copy(), free)


def support_push(point: Any, normal: Any, push: float) -> GraspStatics:
    """Return a Case 2 support at ``point`` [m]: the prescribed wrench ``[h a*; 0]``.

    ``normal`` is ``a*`` (normalised here; world frame), ``push`` is ``h`` [N] from the
    support line (Eq. 10).
    """
    a = as_array(normal, "normal", (3,))
    n = float(np.linalg.norm(a))
    h = float(push)
    if not (n > 0.0 and math.isfinite(h)):
        raise InvalidInputError("a support needs a non-zero normal and a finite push")
    push_dir = np.r_[a / n, np.zeros(3)]
    free = np.linalg.svd(push_dir[:, None], full_matrices=True)[0][:, 1:]  # w . t = 0
    return GraspStatics(as_array(point, "point", (3,)).copy(), free, h * push_dir)


def wrench_space(grasp: GraspStatics) -> FloatArray:
    """Return an orthonormal basis (6, 6 - k) of the wrenches with ``w . t = 0`` (free ``t``)."""
    free = grasp.free
    if free.shape[1] == 0:
        return np.eye(6)
    u, sv, _ = np.linalg.svd(free, full_matrices=True)
    rank = int(np.sum(sv > 1e-12 * max(1.0, float(sv[0]))))
    return u[:, rank:]


def _cross(a: FloatArray, b: FloatArray) -> FloatArray:
    """Return ``a x b`` of two 3-vectors (``np.cross`` costs more than the product here)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]])


def _transfer(point: FloatArray, about: FloatArray) -> FloatArray:
    """Return the 6x6 map of a wrench about ``point`` to the same wrench about ``about``."""
    r = point - about
    A = np.eye(6)
    A[3:, :3] = np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])
    return A


@dataclass(frozen=True)
class LoadSplit:
    """The wrench each hand applies to the object (world frame, about its grasp point).

    Attributes
    ----------
    wrenches : ndarray, shape (n_hands, 6)
        ``[f; m]`` per hand [N, N m], in the order the hands were given.
    length : float
        ``L`` [m] that weighed the moments.
    internal : int
        Dimension of the internal (squeeze) wrenches the rule set to zero.
    residual : float
        Largest balance residual, relative (see :data:`BALANCE_RTOL`).
    """

    wrenches: FloatArray
    length: float
    internal: int
    residual: float


def split_load(hands: Sequence[GraspStatics], load: ObjectLoad, T_world_object: Any,
               *, length: float | None = None) -> LoadSplit:
    """Split the object's weight between the hands by the minimum-norm rule.

    Parameters
    ----------
    hands : sequence of GraspStatics
        The hands holding the object (the leader's first), world frame.
    load : ObjectLoad
        Mass, mass centre (object coordinates) and gravity (world).
    T_world_object : array_like, shape (4, 4)
        The object's pose [m], which places the mass centre.
    length : float, keyword-only, optional
        ``L`` [m]; default: the distance between the first two grasp points
        (:data:`FALLBACK_LENGTH` if they coincide or there is one hand).

    Returns
    -------
    LoadSplit

    Raises
    ------
    UnbalancedLoadError
        The hands' wrench spaces (with the prescribed wrenches) cannot balance the
        weight: the object would slide or turn in the grasps.
    """
    T = as_array(T_world_object, "T_world_object", (4, 4))
    if length is None:
        gap = (float(np.linalg.norm(hands[0].point - hands[1].point)) if len(hands) > 1
               else 0.0)
        length = gap if gap > 1e-9 else FALLBACK_LENGTH
    L = float(length)
    centre = T[:3, :3] @ load.mass_centre + T[:3, 3]
    about = hands[0].point
    weight = load.mass * load.gravity
    rhs = -np.r_[weight, _cross(centre - about, weight)]
    unscale = np.diag([1.0, 1.0, 1.0, L, L, L])  # [f; m / L] -> [f; m]
    blocks, owners = [], []
    for i, hand in enumerate(hands):
        A = _transfer(hand.point, about)
        if hand.wrench is not None:
            rhs = rhs - A @ hand.wrench
            continue
        # The hand's space in scaled coordinates [f; m / L], orthonormal there.
        C, _ = np.linalg.qr(np.linalg.solve(unscale, wrench_space(hand)))
        blocks.append(A @ unscale @ C)
        owners.append((i, C))
    rows = np.diag([1.0, 1.0, 1.0, 1.0 / L, 1.0 / L, 1.0 / L])  # balance in [N, N m / L]
    G = rows @ np.hstack(blocks) if blocks else np.zeros((6, 0))
    b = rows @ rhs
    rank = 0
    mu = np.zeros(G.shape[1])
    if blocks:  # the minimum-norm solution, by one SVD (which also gives the rank)
        u, sv, vt = np.linalg.svd(G, full_matrices=False)
        rank = int(np.sum(sv > 1e-12 * sv[0])) if sv[0] > 0.0 else 0
        mu = vt[:rank].T @ ((u[:, :rank].T @ b) / sv[:rank])
    residual = float(np.max(np.abs(G @ mu - b))) / load.weight
    if not residual <= BALANCE_RTOL:
        raise UnbalancedLoadError(
            f"the grasps cannot hold the load: their wrenches leave {residual:.3g} of the "
            "weight unbalanced (a sliding grasp carries no force along its sliding "
            "direction and no moment about it)")
    out = np.empty((len(hands), 6))
    start = 0
    for i, C in owners:
        k = C.shape[1]
        out[i] = unscale @ C @ mu[start:start + k]
        start += k
    for i, hand in enumerate(hands):
        if hand.wrench is not None:
            out[i] = hand.wrench
    return LoadSplit(out, L, G.shape[1] - rank, residual)
