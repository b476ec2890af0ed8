"""The one step problem: layout, the paper's special case (Eqs. 25-27), bounds and gains."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from dualarm_qp import puma560
from dualarm_qp._compiled import kernel
from dualarm_qp.errors import InvalidInputError, NonFiniteError
from dualarm_qp.se3 import pose_error
from dualarm_qp.step.build import StepBuilder
from dualarm_qp.step.limits import RangeLimit, SpeedLimit
from dualarm_qp.step.options import StepOptions
from dualarm_qp.step.state import DualArmState
from dualarm_qp.task.scene import DualArmTask
from dualarm_qp.task.surfaces import CurvedBar, PlaneBar
from dualarm_qp.task.trajectory import LinearTrajectory


def make_task(rng, surface, *, identity_h1=False, v=(0.05, 0.0, 0.0)):
    """A leader at a random pose and a follower whose base closes the grasp at q_f."""
    leader = puma560(base=pin.SE3(pin.exp3(rng.normal(size=3) * 0.3),
                                  rng.normal(size=3) * 0.2).homogeneous)
    q_l = rng.uniform(leader.q_min, leader.q_max) * 0.6
    q_f = rng.uniform(leader.q_min, leader.q_max) * 0.6
    sigma = rng.uniform(surface.sigma_min, surface.sigma_max)
    H1 = np.eye(4) if identity_h1 else pin.SE3(pin.exp3(rng.normal(size=3)),
                                                rng.normal(size=3) * 0.1).homogeneous
    target = leader.fk(q_l) @ H1 @ surface.pose(sigma)
    follower = puma560(base=target @ pin.SE3(puma560().fk(q_f)).inverse().homogeneous)
    T0 = leader.fk(q_l) @ H1
    traj = LinearTrajectory(T0[:3, 3], np.array(v), R0=T0[:3, :3], tf=1.0)
    return DualArmTask(leader, follower, H1, surface, traj), q_l, q_f, sigma


def options(**kw):
    base = dict(dt=0.01, joint_weights=np.ones(6), grasp_weight=1.0)
    base.update(kw)
    return StepOptions(**base)


@pytest.mark.parametrize("seed", range(4))
def test_paper_special_case_eqs_25_27(seed):
    """A rigid six-joint leader: the closure rows are the paper's hand-assembled ones."""
    rng = np.random.default_rng(seed)
    surface = CurvedBar(0.5, sigma_max=0.3) if seed % 2 else PlaneBar()
    task, q_l, q_f, sigma = make_task(rng, surface)
    exact = seed >= 2
    build = StepBuilder(task, options(exact_orientation=exact)).build(
        DualArmState(0.0, q_l, q_f, sigma))
    A = build.problem.A
    assert A.shape == (12, 13) and build.problem.names[-1] == "m"
    T_l, J_l = task.leader.fk_jacobian(q_l)
    J_f = task.follower.jacobian(q_f)
    target = T_l @ task.H1 @ surface.pose(sigma)
    d = target[:3, 3] - T_l[:3, 3]
    J_lp = J_l.copy()
    J_lp[:3] = J_l[:3] + np.cross(J_l[3:].T, d).T  # Eq. 27: L1 + L2 = -[d]x Ja_l
    R_o = T_l[:3, :3] @ task.H1[:3, :3]
    column = np.r_[R_o @ surface.tangent(sigma),
                   R_o @ surface.angular_rate(sigma) if exact else np.zeros(3)]
    np.testing.assert_allclose(A[6:, :6], -J_lp, atol=1e-14)
    np.testing.assert_allclose(A[6:, 6:12], J_f, atol=1e-14)
    np.testing.assert_allclose(A[6:, 12], -column, atol=1e-14)  # Eq. 26: [J_f, -R_o s*]
    # The leader's rows: the object frame's Jacobian, i.e. J_l carried to the object.
    p_o = (T_l @ task.H1)[:3, 3]
    J_lo = J_l.copy()
    J_lo[:3] = J_l[:3] + np.cross(J_l[3:].T, p_o - T_l[:3, 3]).T
    np.testing.assert_allclose(A[:6, :6], J_lo, atol=1e-14)
    assert not A[:6, 6:].any()


def test_layout_with_a_sliding_leader_grasp():
    rng = np.random.default_rng(2)
    task, q_l, q_f, sigma = make_task(rng, PlaneBar(), identity_h1=True)
    lead = PlaneBar(r_min=(0, 0, -0.4), r_max=(0, 0, 0))
    both = DualArmTask(task.leader, task.follower, np.eye(4), task.surface, task.trajectory,
                       leader_surface=lead)
    builder = StepBuilder(both, options(grasp_speed_max=0.1))
    p = builder.build(DualArmState(0.0, q_l, q_f, sigma, -0.2)).problem
    assert p.names == (*(f"ql{i}" for i in range(1, 7)), *(f"qf{i}" for i in range(1, 7)),
                       "m", "m_l")
    assert p.n_grasp == 2 and p.A.shape == (12, 14)
    assert p.A[:6, 13].any() and not p.A[:6, 12].any()  # the leader's grasp moves the object
    assert p.upper[13] == pytest.approx(0.1) and p.lower[13] == pytest.approx(-0.1)
    with pytest.raises(InvalidInputError, match="H1"):
        DualArmTask(task.leader, task.follower, task.H1 @ task.surface.pose(0.1), task.surface,
                    task.trajectory, leader_surface=lead)


def test_gains_enter_the_right_hand_side():
    rng = np.random.default_rng(5)
    task, q_l, q_f, sigma = make_task(rng, PlaneBar(), v=(0.0, 0.0, 0.0))
    state = DualArmState(0.0, q_l, q_f + 1e-3, sigma)
    plain = StepBuilder(task, options(correction_gain=0.0), leader_gain=0.0).build(state)
    corr = StepBuilder(task, options(correction_gain=20.0), leader_gain=7.0).build(state)
    T_f = task.follower.fk(q_f + 1e-3)
    np.testing.assert_allclose(corr.closure_error,
                               pose_error(task.follower_target(q_l, sigma), T_f), atol=1e-15)
    np.testing.assert_allclose(corr.problem.b[6:] - plain.problem.b[6:],
                               20.0 * corr.closure_error)
    np.testing.assert_allclose(corr.problem.b[:6] - plain.problem.b[:6],
                               7.0 * corr.leader_error)
    # The default closure gain is 1/dt: the whole error in one step, to first order.
    default = StepBuilder(task, options()).build(state)
    np.testing.assert_allclose(default.problem.b[6:], 100.0 * corr.closure_error)


def test_scale_max_scales_the_feed_forward_twist_only():
    rng = np.random.default_rng(6)
    task, q_l, q_f, sigma = make_task(rng, PlaneBar())
    builder = StepBuilder(task, options(), leader_gain=0.0)
    state = DualArmState(0.5, q_l, q_f, sigma)
    full = builder.build(state).problem.b
    half = builder.build(state, scale_max=0.5).problem.b
    np.testing.assert_allclose(full[:3], [0.05, 0.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(half[:6], 0.5 * full[:6], atol=1e-15)
    np.testing.assert_array_equal(half[6:], full[6:])


def test_centre_horizon_and_leader_bounds():
    rng = np.random.default_rng(6)
    task, q_l, q_f, sigma = make_task(rng, PlaneBar())
    state = DualArmState(0.0, q_l, q_f, sigma)
    paper = StepBuilder(task, options()).build(state).problem
    slow = StepBuilder(task, options(centre_horizon=0.5)).build(state).problem
    middle = 0.5 * (task.follower.q_min + task.follower.q_max)
    np.testing.assert_allclose(paper.center[6:12], (middle - q_f) / 0.01)
    np.testing.assert_allclose(slow.center, paper.center * 0.01 / 0.5)
    np.testing.assert_array_equal(slow.lower, paper.lower)
    open_box = StepBuilder(task, options(), leader_bounds=False).build(state).problem
    assert np.isinf(open_box.lower[:6]).all() and not open_box.center[:6].any()
    np.testing.assert_array_equal(open_box.lower[6:], paper.lower[6:])
    with pytest.raises(InvalidInputError):
        options(centre_horizon=0.0)
    with pytest.raises(InvalidInputError, match="leader_joint_weights"):
        StepBuilder(task, options(leader_joint_weights=np.ones(4)))


def test_non_finite_path_time_is_refused():
    rng = np.random.default_rng(4)
    task, q_l, q_f, sigma = make_task(rng, PlaneBar())
    with pytest.raises(NonFiniteError):
        StepBuilder(task, options()).build(DualArmState(float("nan"), q_l, q_f, sigma))


def _rate_bounds_reference(x, x_min, x_max, v_max, dt, recovery_fraction):
    """Eqs. 34-36 written out per variable, as the reference."""
    out = ([], [], [], [])
    for xi, lo_i, hi_i, v in zip(x, x_min, x_max, v_max, strict=True):
        lo, hi = (lo_i - xi) / dt, (hi_i - xi) / dt
        centre = 0.5 * (lo + hi) if np.isfinite(lo) and np.isfinite(hi) else 0.0
        rec = recovery_fraction * v if recovery_fraction > 0 else 0.0
        out[0].append(min(lo, rec) if lo > 0 else max(lo, -v))
        out[1].append(max(hi, -rec) if hi < 0 else min(hi, v))
        out[2].append(centre)
        out[3].append(lo > 0 or hi < 0)
    return tuple(np.array(a) for a in out)


def stacked_box(x, x_min, x_max, v_max, dt, recovery_fraction):
    """The box the range and speed limits give together (the builder's intersection)."""
    ctx = kernel.Context((x_min - x) / dt, (x_max - x) / dt)
    everything = np.ones(x.shape, dtype=bool)
    parts = [RangeLimit("range", everything, v_max, recovery_fraction).constraint(ctx),
             SpeedLimit("speed", v_max).constraint(ctx)]
    lower = np.maximum(parts[0].lower, parts[1].lower)
    upper = np.minimum(parts[0].upper, parts[1].upper)
    return lower, upper, (ctx.rate_lo > 0) | (ctx.rate_hi < 0)


@pytest.mark.parametrize("seed", range(5))
def test_range_and_speed_limits_match_the_per_variable_formula(seed):
    rng = np.random.default_rng(seed)
    n = 9
    x = rng.normal(size=n) * 2.0
    x_min = np.where(rng.random(n) < 0.2, -np.inf, rng.normal(size=n) - 1.0)
    x_max = np.where(rng.random(n) < 0.2, np.inf, rng.normal(size=n) + 1.0)
    v_max = np.where(rng.random(n) < 0.3, np.inf, rng.uniform(0.5, 3.0, n))
    for fraction in (0.0, 0.5):
        with np.errstate(invalid="ignore"):
            got = stacked_box(x, x_min, x_max, v_max, 0.05, fraction)
        want = _rate_bounds_reference(x, x_min, x_max, v_max, 0.05, fraction)
        for g, w in zip(got, (want[0], want[1], want[3]), strict=True):
            np.testing.assert_array_equal(g, w)


@pytest.mark.parametrize("seed", range(5))
def test_a_partial_range_limit_and_the_centring_match_the_per_variable_formula(seed):
    """The range box of some variables only, and the centres (Eqs. 38-40, shrunk from dt
    to a horizon), from the compiled calls the range limit and the cost make."""
    rng = np.random.default_rng(10 + seed)
    n = 11
    x = rng.normal(size=n) * 2.0
    x_min = np.where(rng.random(n) < 0.2, -np.inf, rng.normal(size=n) - 1.0)
    x_max = np.where(rng.random(n) < 0.2, np.inf, rng.normal(size=n) + 1.0)
    v_max = np.where(rng.random(n) < 0.3, np.inf, rng.uniform(0.5, 3.0, n))
    mask = rng.random(n) < 0.6
    with np.errstate(invalid="ignore"):
        lo, hi = (x_min - x) / 0.05, (x_max - x) / 0.05
    ctx = kernel.Context(lo, hi)
    box = RangeLimit("range", mask, v_max, 0.5).constraint(ctx)
    with np.errstate(invalid="ignore"):
        want = _rate_bounds_reference(x, x_min, x_max, np.full(n, np.inf), 0.05, 0.0)
    for i in range(n):
        if not mask[i]:
            assert (box.lower[i], box.upper[i]) == (-np.inf, np.inf)
            continue
        rec = 0.5 * v_max[i]
        assert box.lower[i] == (min(lo[i], rec) if lo[i] > 0 else lo[i])
        assert box.upper[i] == (max(hi[i], -rec) if hi[i] < 0 else hi[i])
    np.testing.assert_array_equal(kernel.centre(lo, hi, np.ones(n, bool), 1.0), want[2])
    shrunk = kernel.centre(lo, hi, mask, 0.25)
    np.testing.assert_array_equal(shrunk, np.where(mask, 0.25 * want[2], 0.0))
