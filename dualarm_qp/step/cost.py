"""The paper's cost: every variable pulled towards the middle of its range (Eqs. 37-40).

    minimise (x - dqhat_c)^T S (x - dqhat_c)                       (Eq. 37)

with ``S`` diagonal (the joint weights and the sliding weight ``s7``) and ``dqhat_c`` the
rate that would bring each variable to the middle of its range in ``centre_horizon``
seconds (Eqs. 38-40; the paper's horizon is one sample). A variable without a finite
range (and the leader's joints, for the paper's methods, whose leader box is open) has
centre 0: the term then asks for the smallest rate. A compiled part
(``kernel.CentringCost``).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._compiled import kernel
from .layout import Layout
from .options import StepOptions

FloatArray = NDArray[np.float64]


class CentringCost(kernel.CentringCost):
    """Eq. 37 with the range centres of Eqs. 38-40.

    Parameters
    ----------
    layout : Layout
        The slices of the decision vector.
    options : StepOptions
        Weights (``leader_joint_weights``, ``joint_weights``, ``grasp_weight``) and the
        centre horizon.
    leader_ranges : bool
        Centre the leader's joints too (False: centre 0, for the paper's methods whose
        leader box is open).

    Attributes
    ----------
    weights : ndarray, shape (n,)
        ``S``'s diagonal (read-only).
    centred : ndarray of bool, shape (n,)
        Which variables are centred (the others' centre is 0).
    shrink : float
        ``dt`` over the centring horizon: the centres' scale.
    """

    name = "centring"

    def __init__(self, layout: Layout, options: StepOptions, *, leader_ranges: bool = True
                 ) -> None:
        w = np.empty(layout.n)
        w[layout.leader] = (1.0 if options.leader_joint_weights is None
                            else options.leader_joint_weights)
        w[layout.follower] = options.joint_weights
        w[layout.grasps] = options.grasp_weight
        w.flags.writeable = False
        centred = np.ones(layout.n, dtype=bool)
        if not leader_ranges:
            centred[layout.leader] = False
        centred.flags.writeable = False
        shrink = options.dt / (options.centre_horizon or options.dt)
        super().__init__(w, centred, shrink)
        self.weights: FloatArray = w
        self.centred: NDArray[np.bool_] = centred
        self.shrink = shrink
        self._args = (layout, options, leader_ranges)

    def __reduce__(self) -> tuple[Any, ...]:
        layout, options, leader_ranges = self._args
        return (_centring, (layout, options, leader_ranges))


def _centring(layout: Layout, options: StepOptions, leader_ranges: bool) -> CentringCost:
    return CentringCost(layout, options, leader_ranges=leader_ranges)


__all__ = ["CentringCost"]
