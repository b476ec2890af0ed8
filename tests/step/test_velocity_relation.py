"""The step's equality keeps the closure to second order (Eqs. 25-27), both grasps sliding too."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from dualarm_qp import puma560
from dualarm_qp.se3 import pose_error
from dualarm_qp.step.bounds import grasp_rate_range
from dualarm_qp.step.build import StepBuilder
from dualarm_qp.step.options import StepOptions
from dualarm_qp.step.state import DualArmState
from dualarm_qp.task.scene import DualArmTask
from dualarm_qp.task.surfaces import CurvedBar, CylinderSurface, PlaneBar
from dualarm_qp.task.trajectory import LinearTrajectory

RNG = np.random.default_rng(7)


def random_task(surface, rng):
    """A leader at a random pose, a follower whose base closes the grasp at q_f."""
    leader = puma560(base=pin.SE3(pin.exp3(rng.normal(size=3) * 0.3),
                                  rng.normal(size=3) * 0.2).homogeneous)
    q_l = rng.uniform(leader.q_min, leader.q_max) * 0.6
    q_f = rng.uniform(leader.q_min, leader.q_max) * 0.6
    sigma = rng.uniform(surface.sigma_min, surface.sigma_max)
    H1 = pin.SE3(pin.exp3(rng.normal(size=3)), rng.normal(size=3) * 0.1).homogeneous
    target = leader.fk(q_l) @ H1 @ surface.pose(sigma)
    follower_local = puma560()
    base_f = target @ pin.SE3(follower_local.fk(q_f)).inverse().homogeneous
    follower = puma560(base=base_f)
    traj = LinearTrajectory(np.zeros(3), np.zeros(3), tf=1.0)
    task = DualArmTask(leader, follower, H1, surface, traj)
    return task, q_l, q_f, sigma


def closure(task, q_l, q_f, sigma, sigma_l=0.0):
    return pose_error(task.follower_target(q_l, sigma, sigma_l), task.follower.fk(q_f))


SURFACES = {
    "plane_bar": lambda: PlaneBar(),
    "cylinder": lambda: CylinderSurface(0.05, azimuth=0.7, sigma_min=-0.2, sigma_max=0.3),
    "curved_bar": lambda: CurvedBar(0.5, sigma_min=-0.2, sigma_max=0.3),
}
LEADER_SURFACES = {
    "rigid": lambda: None,
    "plane_bar": lambda: PlaneBar(r_min=(0, 0, -0.4), r_max=(0, 0, 0)),
    "curved_bar": lambda: CurvedBar(0.8, side="inner", sigma_min=-0.3, sigma_max=0.1),
}


def with_leader_grasp(task, q_l, lead, sigma_l, q_f, sigma):
    """The same arms with the leader's grasp sliding on ``lead``; follower base re-closed."""
    if lead is None:
        return task
    probe = DualArmTask(task.leader, task.follower, np.eye(4), task.surface,
                        task.trajectory, leader_surface=lead)
    target = probe.follower_target(q_l, sigma, sigma_l)
    base_f = target @ pin.SE3(puma560().fk(q_f)).inverse().homogeneous
    return DualArmTask(task.leader, puma560(base=base_f), np.eye(4), task.surface,
                       task.trajectory, leader_surface=lead)


@pytest.mark.parametrize("leader_name", sorted(LEADER_SURFACES))
@pytest.mark.parametrize("surface_name", sorted(SURFACES))
@pytest.mark.parametrize("seed", range(3))
def test_closure_is_kept_to_second_order(surface_name, leader_name, seed):
    """Any motion that meets the step's equality keeps the grasp closed to O(dt^2).

    The sliding grasps are joints of the carried-object model; this holds on straight
    and curved paths, with the follower's grasp sliding and with both sliding.
    """
    rng = np.random.default_rng(seed)
    surface = SURFACES[surface_name]()
    task, q_l, q_f, sigma = random_task(surface, rng)
    lead = LEADER_SURFACES[leader_name]()
    sigma_l = 0.0 if lead is None else rng.uniform(lead.sigma_min, lead.sigma_max)
    task = with_leader_grasp(task, q_l, lead, sigma_l, q_f, sigma)
    assert np.abs(closure(task, q_l, q_f, sigma, sigma_l)).max() < 1e-12
    opts = StepOptions(dt=0.01, joint_weights=np.ones(6), grasp_weight=1.0,
                       velocity_limits=False, exact_orientation=True)
    build = StepBuilder(task, opts, leader_gain=0.0).build(
        DualArmState(0.0, q_l, q_f, sigma, sigma_l))
    A, b = build.problem.A, build.problem.b
    # Any solution of the equality: a particular one plus a random null-space motion.
    x = np.linalg.lstsq(A, b, rcond=None)[0]
    z = np.linalg.svd(A)[2][-1]
    x = x + rng.normal() * 0.3 * z
    assert np.abs(A @ x - b).max() < 1e-10
    m_l = x[13] if lead is not None else 0.0
    errs = []
    for h in (1e-3, 5e-4):
        e = closure(task, q_l + h * x[:6], q_f + h * x[6:12], sigma + h * x[12],
                    sigma_l + h * m_l)
        errs.append(np.abs(e).max())
    # First-order terms cancel: the error is O(h^2), so halving h quarters it.
    assert errs[0] < 1e-4
    assert errs[0] / errs[1] == pytest.approx(4.0, rel=0.05)


def test_without_sliding_column_the_closure_breaks_at_first_order():
    """Sanity check that the test above can fail: move the grasp the wrong way."""
    opts = StepOptions(dt=0.01, joint_weights=np.ones(6), grasp_weight=1.0)
    for seed in range(50):  # a state where sliding needs little joint motion
        task, q_l, q_f, sigma = random_task(PlaneBar(), np.random.default_rng(seed))
        build = StepBuilder(task, opts, leader_gain=0.0).build(DualArmState(0.0, q_l, q_f, sigma))
        z = np.linalg.svd(build.problem.A)[2][-1]
        if abs(z[12]) > 0.5:
            break
    x = 0.1 * z / z[12]  # slides at 0.1 m/s, meets A x = b = 0
    errs = []
    for h in (1e-3, 5e-4):
        e = closure(task, q_l + h * x[:6], q_f + h * x[6:12], sigma - h * x[12])
        errs.append(np.abs(e).max())
    assert errs[0] / errs[1] == pytest.approx(2.0, rel=0.1)


def test_paper_frozen_orientation_differs_on_curved_bar_only():
    rng = np.random.default_rng(11)
    for surface, curved in ((PlaneBar(), False), (CurvedBar(0.5, sigma_max=0.3), True)):
        task, q_l, q_f, sigma = random_task(surface, rng)
        state = DualArmState(0.0, q_l, q_f, sigma)
        a = StepBuilder(task, StepOptions(dt=0.01, joint_weights=np.ones(6), grasp_weight=1.0,
                                          exact_orientation=True)).build(state)
        b = StepBuilder(task, StepOptions(dt=0.01, joint_weights=np.ones(6),
                                          grasp_weight=1.0)).build(state)
        diff = np.abs(a.problem.A[9:, 12] - b.problem.A[9:, 12]).max()
        assert (diff > 1e-3) == curved
        assert not b.problem.A[9:, 12].any()


def test_grasp_rate_range_matches_eqs_30_31():
    # Paper bar: s* = z, r in [0, 400] mm, r* = 100 mm, dT = 31 ms.
    lo, hi = grasp_rate_range(np.array([0, 0, 0.1]), np.array([0, 0, 1.0]),
                              np.zeros(3), np.array([0, 0, 0.4]), 0.031)
    assert lo == pytest.approx(-0.1 / 0.031)
    assert hi == pytest.approx(0.3 / 0.031)
    # A negative component swaps the candidates; zero components are skipped.
    lo, hi = grasp_rate_range(np.array([0.1, 0, 0.1]), np.array([-0.6, 0, 0.8]),
                              np.zeros(3), np.full(3, 0.4), 1.0)
    assert lo == pytest.approx(max(-0.3 / 0.6, -0.1 / 0.8))
    assert hi == pytest.approx(min(0.1 / 0.6, 0.3 / 0.8))


def test_start_outside_box_is_recovering_and_never_moves_further_out():
    from test_step_builder import stacked_box

    x = np.array([-1.0, 0.5, 2.0])
    lo, hi, rec = stacked_box(x, np.zeros(3), np.ones(3), np.full(3, 4.0), 0.1, 0.5)
    assert rec.tolist() == [True, False, True]
    assert lo[0] > 0 and hi[2] < 0  # can only move back inside
    assert lo[0] == pytest.approx(2.0) and hi[2] == pytest.approx(-2.0)  # 0.5 * speed limit
    assert lo[1] == pytest.approx(-4.0) and hi[1] == pytest.approx(4.0)
    # Unlimited speed: return all the way in one step.
    lo, hi, _ = stacked_box(x, np.zeros(3), np.ones(3), np.full(3, np.inf), 0.1, 0.5)
    assert lo[0] == pytest.approx(10.0) and hi[2] == pytest.approx(-10.0)
    # The default (no forced return): the box only forbids moving further out, so it
    # always contains 0 and a step stays feasible at task scale 0.
    for v in (4.0, np.inf):
        lo, hi, rec = stacked_box(x, np.zeros(3), np.ones(3), np.full(3, v), 0.1, 0.0)
        assert lo[0] == 0.0 and hi[2] == 0.0
        assert hi[0] == pytest.approx(min(v, 20.0)) and lo[2] == pytest.approx(max(-v, -20.0))
        assert rec.tolist() == [True, False, True]
