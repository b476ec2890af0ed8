"""Arm models and kinematics: DH arms, the PUMA 560, inverse kinematics."""

from .arm import DHTable, SerialArm
from .ik import IKResult, ik_dls
from .puma560 import puma560
from .puma_ik import IKSolution, ik_branch, puma560_ik, puma560_indicators

__all__ = [
    "DHTable",
    "IKResult",
    "IKSolution",
    "SerialArm",
    "ik_branch",
    "ik_dls",
    "puma560",
    "puma560_ik",
    "puma560_indicators",
]
