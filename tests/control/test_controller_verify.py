"""The controller applies only solutions certified once, with its own tolerances."""

from __future__ import annotations

import importlib

import numpy as np
import pinocchio as pin
import pytest

from dualarm_qp import puma560
from dualarm_qp.control.controller import DualArmController
from dualarm_qp.solvers import get_solver
from dualarm_qp.solvers.base import Status, StepSolution, Tolerance
from dualarm_qp.solvers.certify import certify, verdict_fields
from dualarm_qp.step.options import StepOptions
from dualarm_qp.step.problem import StepProblem
from dualarm_qp.step.state import DualArmState
from dualarm_qp.task.scene import DualArmTask
from dualarm_qp.task.surfaces import PlaneBar
from dualarm_qp.task.trajectory import LinearTrajectory


def stepped(controller, state, steps: int) -> list:
    """The outputs of ``steps`` steps from ``state``, each applied for one sample."""
    outs = []
    for _ in range(steps):
        out = controller.step(state)
        outs.append(out)
        state = state.advanced(out, controller.options.dt)
    return outs


def make_controller(solver, **kw):
    """A leader and a follower closed on the paper's bar at sigma = 0.2 m."""
    leader = puma560()
    q_l = np.array([0.3, -0.5, 0.4, 0.2, 0.6, -0.3])
    q_f = np.array([-0.2, -0.4, 0.5, -0.3, 0.5, 0.4])
    surface = PlaneBar()
    sigma = 0.2
    target = leader.fk(q_l) @ surface.pose(sigma)
    follower = puma560(base=target @ pin.SE3(puma560().fk(q_f)).inverse().homogeneous)
    start = leader.fk(q_l)
    traj = LinearTrajectory(start[:3, 3], np.array([0.02, 0.0, 0.0]), R0=start[:3, :3], tf=1.0)
    task = DualArmTask(leader, follower, np.eye(4), surface, traj)
    opts = StepOptions(dt=0.01, joint_weights=np.ones(6), grasp_weight=10.0)
    return DualArmController(task, solver, opts, **kw), DualArmState(0.0, q_l, q_f, sigma)


class Unverified:
    """Claims OPTIMAL for a fixed x without verifying it."""

    name = "unverified"

    def __init__(self, shift: float) -> None:
        self.shift = shift

    def solve(self, problem: StepProblem) -> StepSolution:
        x = get_solver("nullspace").solve(problem).x + self.shift
        return StepSolution(x=x, status=Status.OPTIMAL, solver=self.name)


class VerifiedWith:
    """Certifies its (wrong) answer, but against tolerances of its own."""

    name = "verified_with"

    def __init__(self, tol: Tolerance, shift: float) -> None:
        self.tol, self.shift = tol, shift

    def solve(self, problem: StepProblem) -> StepSolution:
        x = get_solver("nullspace").solve(problem).x + self.shift
        return certify(problem, StepSolution(x=x, status=Status.OPTIMAL), self.tol)


@pytest.mark.parametrize("name", ["nullspace", "qp:daqp", "sns"])
def test_a_step_is_certified_once(monkeypatch, name):
    controller, state = make_controller(get_solver(name))
    calls = []

    def counting_decision(*args, **kwargs):
        calls.append(args)
        return verdict_fields(*args, **kwargs)

    # Every certification ends in the one decision (certify's verdict, or the kernel
    # call that solves and certifies the exact step): patched in every module that
    # calls it.
    for module in ("dualarm_qp.solvers.certify", "dualarm_qp.solvers.nullspace"):
        monkeypatch.setattr(importlib.import_module(module), "verdict_fields",
                            counting_decision)
    out = controller.step(state)
    assert out.applied and out.status in (Status.OPTIMAL, Status.RECOVERING)
    assert out.solution.verified_with == controller.tolerance
    assert len(calls) == 1


@pytest.mark.parametrize("shift", [1e-3, 1e6])
def test_an_unverified_wrong_solution_is_flagged_and_not_applied(shift):
    controller, state = make_controller(Unverified(shift))
    out = controller.step(state)
    assert out.status is Status.VIOLATION
    assert not out.applied
    assert np.array_equal(out.qf_dot, np.zeros(6)) and out.m == 0.0 and out.scale == 0.0
    assert out.solution.verified_with == controller.tolerance


def test_a_solution_certified_with_looser_tolerances_is_certified_again():
    loose = Tolerance(equality=1.0, bounds=1e9)
    controller, state = make_controller(VerifiedWith(loose, 1e-3))
    out = controller.step(state)
    assert out.status is Status.VIOLATION and not out.applied
    assert out.solution.verified_with == controller.tolerance


def test_an_unverified_correct_solution_is_applied():
    controller, state = make_controller(Unverified(0.0))
    reference, _ = make_controller(get_solver("nullspace"))
    out, ref = controller.step(state), reference.step(state)
    assert out.applied and out.status is ref.status
    np.testing.assert_array_equal(out.qf_dot, ref.qf_dot)
    assert out.solution.objective == pytest.approx(ref.solution.objective)
