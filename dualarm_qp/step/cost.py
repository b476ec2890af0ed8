"""The paper's cost: every variable pulled towards the middle of its range (Eqs. 37-40).

    minimise (x - dqhat_c)^T S (x - dqhat_c)                       (Eq. 37)

with ``S`` diagonal (the joint weights and the sliding weight ``s7``) and ``dqhat_c`` the
rate that would bring each variable to the middle of its range in ``centre_horizon``
seconds (Eqs. 38-40; the paper's horizon is one sample). A variable without a finite
range (and the leader's joints, for the paper's methods, whose leader box is open) has
centre 0: the term then asks for the smallest rate.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .._compiled import kernel
from .context import StepContext
from .layout import Layout
from .options import StepOptions
from .parts import Quadratic

FloatArray = NDArray[np.float64]


class CentringCost:
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
    """

    name = "centring"

    def __init__(self, layout: Layout, options: StepOptions, *, leader_ranges: bool = True
                 ) -> None:
        w = np.empty(layout.n)
        w[layout.leader] = (1.0 if options.leader_joint_weights is None
                            else options.leader_joint_weights)
        w[layout.follower] = options.joint_weights
        w[layout.grasps] = options.grasp_weight
        w.flags.writeable = False  # shared by every problem
        self.weights = w
        centred = np.ones(layout.n, dtype=bool)
        if not leader_ranges:
            centred[layout.leader] = False
        centred.flags.writeable = False
        #: Which variables are centred (the others' centre is 0).
        self.centred = centred
        #: ``dt`` over the centring horizon: the centres' scale.
        self.shrink = options.dt / (options.centre_horizon or options.dt)

    def __setstate__(self, state: dict[str, object]) -> None:
        # A pickle (and copy.deepcopy) gives numpy arrays back writeable: the weights and
        # the centred flags stay read-only (the exact solver's kernel settings are kept
        # for this very weights array).
        self.__dict__.update(state)
        self.weights.flags.writeable = False
        self.centred.flags.writeable = False

    def quadratic(self, ctx: StepContext) -> Quadratic:
        """Weights ``S`` and centres ``dqhat_c`` [rad/s, m/s] at this step."""
        # The middle of each centred variable's finite rate range, scaled from dt to the
        # centring horizon (one compiled call, src/kernel/boxes.cpp).
        return Quadratic(self.weights, kernel.centre(ctx.rate_lo, ctx.rate_hi, self.centred,
                                                     self.shrink))


__all__ = ["CentringCost"]
