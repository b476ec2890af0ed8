"""The step problem layer.

Only :class:`StepProblem` is imported here, so that solvers can depend on it without
importing any robot or task code. The builder lives in :mod:`dualarm_qp.step.build`.
"""

from .problem import StepProblem

__all__ = ["StepProblem"]
