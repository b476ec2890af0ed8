"""The decision vector of one step: which entries belong to which variable.

Every step solves for one vector ``x`` holding both arms' joint rates and the sliding
speed of every sliding grasp, in this order:

    x = [ql_dot (n_l), qf_dot (n_f), m (the follower's grasp), m_l (the leader's grasp,
         if it slides)]

in [rad/s] and [m/s]. :class:`Layout` is the one place that knows these slices: tasks,
limits, the controller and the recorded trace read the parts of ``x`` through it, and
no index arithmetic on ``x`` happens anywhere else.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidInputError, ShapeError

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class Layout:
    """Slices of the decision vector.

    Parameters
    ----------
    n_l, n_f : int
        Joints of the leader and of the follower.
    n_grasp : int
        Sliding grasps: 1 (the follower's) or 2 (the leader's slides too).

    Attributes
    ----------
    n : int
        Length of ``x``.
    leader, follower : slice
        The joint rates of each arm [rad/s].
    joints : slice
        Both arms' joint rates.
    grasps : slice
        Every sliding speed [m/s] (the follower's first).
    grasp_follower : int
        Index of the follower's sliding speed ``m``.
    grasp_leader : int or None
        Index of the leader's sliding speed ``m_l`` (None for a rigid leader grasp).
    names : tuple of str
        ``ql1.., qf1.., m`` and ``m_l`` if the leader's grasp slides.
    """

    n_l: int
    n_f: int
    n_grasp: int = 1
    n: int = field(init=False)
    leader: slice = field(init=False)
    follower: slice = field(init=False)
    joints: slice = field(init=False)
    grasps: slice = field(init=False)
    grasp_follower: int = field(init=False)
    grasp_leader: int | None = field(init=False)
    names: tuple[str, ...] = field(init=False)

    def __post_init__(self) -> None:
        if self.n_l < 1 or self.n_f < 1 or self.n_grasp not in (1, 2):
            raise InvalidInputError(f"a layout needs joints on both arms and 1 or 2 grasps, "
                                    f"got {self.n_l}, {self.n_f}, {self.n_grasp}")
        j = self.n_l + self.n_f
        set_ = object.__setattr__
        set_(self, "n", j + self.n_grasp)
        set_(self, "leader", slice(0, self.n_l))
        set_(self, "follower", slice(self.n_l, j))
        set_(self, "joints", slice(0, j))
        set_(self, "grasps", slice(j, j + self.n_grasp))
        set_(self, "grasp_follower", j)
        set_(self, "grasp_leader", j + 1 if self.n_grasp == 2 else None)
        set_(self, "names", (*(f"ql{i + 1}" for i in range(self.n_l)),
                             *(f"qf{i + 1}" for i in range(self.n_f)),
                             "m", *(("m_l",) if self.n_grasp == 2 else ())))

    def split(self, x: FloatArray) -> tuple[FloatArray, FloatArray, float, float]:
        """``(ql_dot, qf_dot, m, m_l)`` of ``x`` (copies; ``m_l`` is 0 for a rigid grasp).

        Raises
        ------
        ShapeError
            ``x`` is not of length :attr:`n`.
        """
        if x.shape != (self.n,):
            raise ShapeError("x", (self.n,), x.shape)
        m_l = float(x[self.grasp_leader]) if self.grasp_leader is not None else 0.0
        return (x[self.leader].copy(), x[self.follower].copy(),
                float(x[self.grasp_follower]), m_l)

    def join(self, ql_dot: FloatArray, qf_dot: FloatArray, m: float, m_l: float = 0.0
             ) -> FloatArray:
        """Return the decision vector of the given rates [rad/s, m/s]."""
        x = np.empty(self.n)
        x[self.leader] = ql_dot
        x[self.follower] = qf_dot
        x[self.grasp_follower] = m
        if self.grasp_leader is not None:
            x[self.grasp_leader] = m_l
        return x

    def positions(self, q_l: FloatArray, q_f: FloatArray, sigma: float,
                  sigma_l: float = 0.0) -> FloatArray:
        """Return the positions the variables are rates of: joints [rad], grasp coordinates [m]."""
        return self.join(q_l, q_f, sigma, sigma_l)


__all__ = ["Layout"]
