"""dualarm_qp: coordinate two robot arms carrying one object, with a sliding grasp.

The names below are the public API; ``docs/api.md`` lists them with their units (SI:
m, rad, s). Only the errors are imported with the package; every other name is
imported on first use (``dualarm_qp.rollout``, ``from dualarm_qp import puma560``), so
``import dualarm_qp`` loads neither NumPy nor the kinematics and collision libraries
(Pinocchio, Coal), nor the QP backends, SciPy or matplotlib: the command line's parser
and a run's drawing process, forked as the command starts, import only what they use.
"""

# No ``from __future__ import annotations`` and private aliases for the helpers: the
# module's attributes, like ``dir(dualarm_qp)``, are the public API and little else.
import os as _os
import sys as _sys

# Every matrix of a step is at most a few dozen wide: a threaded BLAS only adds thread
# hand-offs, which on a loaded machine cost 100x the arithmetic (a 3 x 3 triangular
# solve measured 226 us with OpenBLAS's threads, 1.9 us with one). Ask for one thread
# unless the user chose otherwise or NumPy was loaded before us (then it is too late).
if "numpy" not in _sys.modules:
    for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        _os.environ.setdefault(_var, "1")

from typing import TYPE_CHECKING as _TYPE_CHECKING

from ._lazy import lazy_names as _lazy_names
from .errors import (
    ConfigError,
    DualArmError,
    IKError,
    InfeasibleStepError,
    InvalidInputError,
    KinematicsError,
    LimitsError,
    NonFiniteError,
    PairingError,
    ShapeError,
    SolverError,
    SolverNotFoundError,
    SupportLostError,
)

if _TYPE_CHECKING:
    from .collision import CollisionScene, CollisionSettings
    from .control import ControlOutput, DualArmController, RolloutResult, RunLimits, rollout
    from .experiments import Experiment, build_experiment, load_config, run_experiment
    from .geometry import Box, Capsule, sphere
    from .kinematics import (
        DHTable,
        RobotModelError,
        SerialArm,
        example_robot_arm,
        ik_dls,
        puma560,
        puma560_ik,
        urdf_arm,
    )
    from .poses import pose
    from .solvers import (
        Status,
        StepSolution,
        StepSolver,
        available_solvers,
        get_solver,
        list_solvers,
        solve_step,
    )
    from .solvers.registry import SolverOptionError
    from .step.context import StepContext
    from .step.layout import Layout
    from .step.options import StepOptions
    from .step.parts import Constraint, CostTerm, Equality, Limit, Quadratic, Task
    from .step.problem import StepProblem
    from .step.state import DualArmState
    from .task.scene import DualArmTask
    from .task.surfaces import CurvedBar, CylinderSurface, GraspSurface, PlaneBar
    from .task.trajectory import LinearTrajectory, Trajectory, WaypointTrajectory

__version__ = "0.1.0"

#: Names imported on first access, and the subpackage each comes from.
_LAZY = {
    "DHTable": "kinematics",
    "RobotModelError": "kinematics",
    "SerialArm": "kinematics",
    "example_robot_arm": "kinematics",
    "ik_dls": "kinematics",
    "puma560": "kinematics",
    "puma560_ik": "kinematics",
    "urdf_arm": "kinematics",
    "pose": "poses",
    "Box": "geometry",
    "Capsule": "geometry",
    "CollisionScene": "collision",
    "CollisionSettings": "collision",
    "sphere": "geometry",
    "CurvedBar": "task.surfaces",
    "CylinderSurface": "task.surfaces",
    "DualArmTask": "task.scene",
    "GraspSurface": "task.surfaces",
    "LinearTrajectory": "task.trajectory",
    "PlaneBar": "task.surfaces",
    "Trajectory": "task.trajectory",
    "WaypointTrajectory": "task.trajectory",
    "DualArmState": "step.state",
    "StepOptions": "step.options",
    "StepProblem": "step.problem",
    "ControlOutput": "control",
    "DualArmController": "control",
    "RolloutResult": "control",
    "RunLimits": "control",
    "rollout": "control",
    "Status": "solvers",
    "StepSolution": "solvers",
    "StepSolver": "solvers",
    "available_solvers": "solvers",
    "get_solver": "solvers",
    "list_solvers": "solvers",
    "Constraint": "step.parts",
    "CostTerm": "step.parts",
    "Equality": "step.parts",
    "Limit": "step.parts",
    "Quadratic": "step.parts",
    "Task": "step.parts",
    "StepContext": "step.context",
    "Layout": "step.layout",
    "solve_step": "solvers",
    "SolverOptionError": "solvers.registry",
    "Experiment": "experiments",
    "build_experiment": "experiments",
    "load_config": "experiments",
    "run_experiment": "experiments",
}

__all__ = [
    # kinematics
    "DHTable",
    "SerialArm",
    "example_robot_arm",
    "ik_dls",
    "puma560",
    "puma560_ik",
    "urdf_arm",
    # poses
    "pose",
    # collision geometry
    "Box",
    "Capsule",
    "CollisionScene",
    "CollisionSettings",
    "sphere",
    # task
    "CurvedBar",
    "CylinderSurface",
    "DualArmTask",
    "GraspSurface",
    "LinearTrajectory",
    "PlaneBar",
    "Trajectory",
    "WaypointTrajectory",
    # step
    "Constraint",
    "CostTerm",
    "DualArmState",
    "Equality",
    "Layout",
    "Limit",
    "Quadratic",
    "StepContext",
    "StepOptions",
    "StepProblem",
    "Task",
    # solvers
    "Status",
    "StepSolution",
    "StepSolver",
    "available_solvers",
    "get_solver",
    "list_solvers",
    "solve_step",
    # control
    "ControlOutput",
    "DualArmController",
    "RolloutResult",
    "RunLimits",
    "rollout",
    # experiments
    "Experiment",
    "build_experiment",
    "load_config",
    "run_experiment",
    # errors
    "ConfigError",
    "DualArmError",
    "IKError",
    "InfeasibleStepError",
    "InvalidInputError",
    "KinematicsError",
    "LimitsError",
    "NonFiniteError",
    "PairingError",
    "RobotModelError",
    "ShapeError",
    "SolverError",
    "SolverNotFoundError",
    "SolverOptionError",
    "SupportLostError",
    "__version__",
]


#: Import a name of :data:`_LAZY` from its subpackage on first access.
__getattr__ = _lazy_names(__name__, globals(), _LAZY)


def __dir__() -> list[str]:
    """List the public names, the lazy ones included (for completion and ``dir()``).

    Only :data:`__all__`: not the subpackages imported along the way (``errors``,
    ``task``, ...), nor this module's own helpers. Subpackages are imported as usual
    (``import dualarm_qp.viz``).
    """
    return sorted(__all__)
