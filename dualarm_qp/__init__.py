"""dualarm_qp: coordinate two robot arms carrying one object, with a sliding grasp."""

from .errors import DualArmError
from .kinematics import (
    DHTable,
    SerialArm,
    example_robot_arm,
    ik_dls,
    puma560,
    puma560_ik,
    urdf_arm,
)

__version__ = "0.1.0"

__all__ = [
    "DHTable",
    "DualArmError",
    "SerialArm",
    "__version__",
    "example_robot_arm",
    "ik_dls",
    "puma560",
    "puma560_ik",
    "urdf_arm",
]
