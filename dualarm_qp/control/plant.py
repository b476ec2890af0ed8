"""What the rollout drives: by default the model itself, or a plant that measures.

Without a plant, :func:`~dualarm_qp.control.rollout.rollout` integrates each command
exactly (explicit Euler, :meth:`DualArmState.advanced
<dualarm_qp.step.state.DualArmState.advanced>`): the measured state is the commanded
one. A :class:`Plant` takes the command instead and hands back what it measured after
``dt``, e.g. the MuJoCo simulation of :mod:`dualarm_qp.physics.plant`.
"""

from __future__ import annotations

from typing import Protocol

from ..step.state import Command, DualArmState


class Plant(Protocol):
    """A plant the rollout drives at the controller's ``dt``."""

    def reset(self, state: DualArmState, dt: float) -> None:
        """Put the plant at ``state`` (at rest) before the first sample; ``dt`` [s]."""

    def advance(self, state: DualArmState, command: Command, dt: float) -> DualArmState:
        """Apply ``command`` for ``dt`` seconds from ``state``; return the measured state.

        The returned path time is ``state.t + dt * command.scale`` (the path time is the
        controller's, not measured).
        """


__all__ = ["Plant"]
