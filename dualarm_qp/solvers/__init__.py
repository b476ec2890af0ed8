"""Step solvers: every redundancy-resolution method behind one interface and a registry.

Importing this package registers every solver module:

``reference``      the paper's Eq. 29 (pseudoinverse + optimal null-space term), no bounds
``fixed_grasp``    Zheng and Luh: the grasp does not slide, no bounds
``nullspace``      exact QP solution by null-space parametrisation (closed form for d = 1;
                   boxes and general rows)
``qp:<backend>``   the QP of Eq. 37 through qpsolvers (osqp, proxsuite, daqp, ...)
``sns``            Saturation in the Null Space (hard bounds, not a QP; scaled by the policy;
                   boxes only)

and :func:`solve_step` applies an infeasible-step policy around any of them.
"""

# Registration order is the listing order: the paper's methods, then the hard-bound ones.
from . import reference  # noqa: I001, F401  (registration)
from . import fixed_grasp, nullspace, sns, qp  # noqa: F401  (registration)
from .base import Status, StepSolution, StepSolver, Tolerance
from .certify import certify
from .policy import POLICIES, Policy, solve_step
from .registry import (
    CertifiedSolver,
    SolverInfo,
    available_solvers,
    certified,
    get_solver,
    list_solvers,
    register,
    solver_info,
)

__all__ = [
    "POLICIES",
    "CertifiedSolver",
    "Policy",
    "SolverInfo",
    "StepSolution",
    "StepSolver",
    "Status",
    "Tolerance",
    "available_solvers",
    "certified",
    "certify",
    "get_solver",
    "list_solvers",
    "register",
    "solve_step",
    "solver_info",
]
