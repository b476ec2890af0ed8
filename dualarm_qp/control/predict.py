"""A measurement some samples late, brought forward by the commands given since.

A cell's measurement often reaches its controller late: a driver at another rate, a
network hop. With ``d`` samples of delay the controller computes each command from the
state ``d`` samples old; its feedback (the tracking and closure gains ``K``, with ``K
dt`` up to 1) then acts on errors it has already corrected, and the loop rings: at one
sample of delay and ``K dt = 1`` the loop is on the edge of stability (it oscillates at
a sixth of the sample rate), beyond it unstable. The commands given since the measured
sample are known, so the state they lead to is predicted (a Smith predictor): the
measured joints and grasps plus ``dt`` times each command applied since, the path time
the controller's own. What the prediction cannot know (the servos' lag, a sag under
load) still reaches the controller, ``d`` samples late.
"""

from __future__ import annotations

from collections import deque

import numpy as np
from numpy.typing import NDArray

from ..step.state import Command, DualArmState

FloatArray = NDArray[np.float64]


class CommandHistory:
    """The last ``delay`` commands applied, and the state they lead to from a late one.

    Parameters
    ----------
    delay : int
        Samples the measurement is late (0: no prediction).
    """

    def __init__(self, delay: int) -> None:
        self.delay = int(delay)
        self._moves: deque[tuple[FloatArray, FloatArray, float, float]] = deque(
            maxlen=max(self.delay, 1))

    def clear(self) -> None:
        """Forget every command (a new run)."""
        self._moves.clear()

    def push(self, command: Command, dt: float) -> None:
        """Remember that ``command`` was applied for ``dt`` [s]."""
        if self.delay:
            self._moves.append((dt * np.asarray(command.ql_dot, dtype=float),
                                dt * np.asarray(command.qf_dot, dtype=float),
                                dt * float(command.m), dt * float(command.m_leader)))

    def predict(self, late: DualArmState, samples: int) -> DualArmState:
        """Return ``late`` (measured ``samples`` samples ago) moved by the commands since.

        ``samples`` is at most :attr:`delay` (fewer at the start of a run, when the
        measurement handed is the start's); the path time is ``late``'s.
        """
        q_l, q_f = np.asarray(late.q_l, dtype=float), np.asarray(late.q_f, dtype=float)
        sigma, sigma_l = float(late.sigma), float(late.sigma_leader)
        for dl, df, dm, dml in list(self._moves)[len(self._moves) - samples:]:
            q_l, q_f, sigma, sigma_l = q_l + dl, q_f + df, sigma + dm, sigma_l + dml
        return DualArmState(late.t, q_l, q_f, sigma, sigma_l)


__all__ = ["CommandHistory"]
