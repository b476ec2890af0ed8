"""Arm models and kinematics (on Pinocchio): DH arms, URDF chains, the PUMA 560, IK."""

from .arm import DHTable, SerialArm
from .ik import IKResult, ik_dls
from .puma560 import puma560
from .puma_ik import IKSolution, ik_branch, puma560_ik, puma560_indicators
from .robots import EXAMPLE_ROBOTS, RobotModelError, example_robot_arm, urdf_arm

__all__ = [
    "EXAMPLE_ROBOTS",
    "DHTable",
    "IKResult",
    "IKSolution",
    "RobotModelError",
    "SerialArm",
    "example_robot_arm",
    "ik_branch",
    "ik_dls",
    "puma560",
    "puma560_ik",
    "puma560_indicators",
    "urdf_arm",
]
