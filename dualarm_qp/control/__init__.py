"""The per-step controller and the rollout built on it."""

from .controller import ControlOutput, DualArmController, StepTimes
from .realised import LimitReport
from .rollout import Failure, RolloutResult, RunLimits, rollout
from .trace import Trace

__all__ = ["ControlOutput", "DualArmController", "Failure", "LimitReport", "RolloutResult",
           "RunLimits", "StepTimes", "Trace", "rollout"]
