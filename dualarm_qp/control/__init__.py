"""The per-step controller and the rollout built on it."""

from .controller import ControlOutput, DualArmController, StepTimes
from .rollout import RolloutResult, Trace, rollout

__all__ = ["ControlOutput", "DualArmController", "RolloutResult", "StepTimes", "Trace", "rollout"]
