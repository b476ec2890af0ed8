"""The step builder's fast paths give the same problems as the checked ones."""

from __future__ import annotations

import dataclasses

import numpy as np
import pinocchio as pin
import pytest

from dualarm_qp import puma560
from dualarm_qp.errors import NonFiniteError, ShapeError
from dualarm_qp.se3 import compose_rows, pose_error, pose_error_rows
from dualarm_qp.step.build import (
    DualArmState,
    StepBuilder,
    StepOptions,
    build_step,
    rate_bounds,
)
from dualarm_qp.step.problem import StepProblem
from dualarm_qp.task.scene import DualArmTask
from dualarm_qp.task.surfaces import CurvedBar, PlaneBar
from dualarm_qp.task.trajectory import LinearTrajectory

FIELDS = [f.name for f in dataclasses.fields(StepProblem)]


def make_task(rng, surface, *, identity_h1=False):
    """A leader at a random pose and a follower whose base closes the grasp at q_f."""
    leader = puma560(base=pin.SE3(pin.exp3(rng.normal(size=3) * 0.3),
                                  rng.normal(size=3) * 0.2).homogeneous)
    q_l = rng.uniform(leader.q_min, leader.q_max) * 0.6
    q_f = rng.uniform(leader.q_min, leader.q_max) * 0.6
    sigma = rng.uniform(surface.sigma_min, surface.sigma_max)
    H1 = pin.SE3(pin.exp3(rng.normal(size=3)), rng.normal(size=3) * 0.1).homogeneous
    if identity_h1:
        H1 = np.eye(4)
    target = leader.fk(q_l) @ H1 @ surface.pose(sigma)
    follower = puma560(base=target @ pin.SE3(puma560().fk(q_f)).inverse().homogeneous)
    traj = LinearTrajectory(np.zeros(3), np.array([0.05, 0.0, 0.0]), tf=1.0)
    return DualArmTask(leader, follower, H1, surface, traj), q_l, q_f, sigma


def build(task, state, ql_dot, opts, x_prev=None):
    return build_step(task, state, ql_dot, opts, leader_kin=task.leader.fk_jacobian(state.q_l),
                      follower_kin=task.follower.fk_jacobian(state.q_f), x_prev=x_prev)


def assert_same_problem(a: StepProblem, b: StepProblem, *, timed: bool = True) -> None:
    for name in FIELDS if timed else [f for f in FIELDS if f != "build_time"]:
        va, vb = getattr(a, name), getattr(b, name)
        if isinstance(va, np.ndarray):
            assert isinstance(vb, np.ndarray) and va.dtype == vb.dtype, name
            np.testing.assert_array_equal(va, vb, err_msg=name)
        else:
            assert va == vb, name


@pytest.mark.parametrize("seed", range(6))
def test_trusted_problem_equals_the_checked_constructor(seed):
    rng = np.random.default_rng(seed)
    surface = CurvedBar(0.5, sigma_max=0.3) if seed % 2 else PlaneBar()
    task, q_l, q_f, sigma = make_task(rng, surface, identity_h1=seed % 3 == 0)
    opts = StepOptions(dt=0.01, joint_weights=rng.uniform(0.5, 2.0, 6), grasp_weight=3.0,
                       velocity_limits=bool(seed % 2), grasp_speed_max=0.2,
                       correction_gain=10.0 * (seed % 3), exact_orientation=seed == 5)
    x_prev = rng.normal(size=7) if seed % 2 else None
    made = build(task, DualArmState(0.0, q_l, q_f + (3.0 if seed == 4 else 0.0), sigma),
                 rng.normal(size=6), opts, x_prev).problem
    checked = StepProblem(**{name: getattr(made, name) for name in FIELDS})
    assert_same_problem(made, checked)
    assert_same_problem(made, dataclasses.replace(made))  # replace() runs the checks


def test_builder_reused_over_steps_equals_one_off_builds():
    rng = np.random.default_rng(3)
    task, q_l, q_f, sigma = make_task(rng, PlaneBar())
    opts = StepOptions(dt=0.01, joint_weights=np.ones(6), grasp_weight=1.0, correction_gain=5.0)
    builder = StepBuilder(task, opts)
    for k in range(4):
        state = DualArmState(0.1 * k, q_l + 0.01 * k, q_f - 0.01 * k, sigma)
        lk, fk = task.leader.fk_jacobian(state.q_l), task.follower.fk_jacobian(state.q_f)
        ql_dot = rng.normal(size=6)
        a = builder.build(state, ql_dot, leader_kin=lk, follower_kin=fk)
        b = build_step(task, state, ql_dot, opts, leader_kin=lk, follower_kin=fk)
        assert_same_problem(a.problem, b.problem, timed=False)
        np.testing.assert_array_equal(a.recovering, b.recovering)
        np.testing.assert_array_equal(a.closure_error, b.closure_error)
        np.testing.assert_array_equal(a.leader_rhs, b.leader_rhs)
    # Problems of different steps share no mutable array.
    p1 = builder.build(state, ql_dot, leader_kin=lk, follower_kin=fk).problem
    p2 = builder.build(state, ql_dot, leader_kin=lk, follower_kin=fk).problem
    for name in ("A", "b", "center", "lower", "upper"):
        assert not np.shares_memory(getattr(p1, name), getattr(p2, name))
    assert not p1.weights.flags.writeable


def test_builder_rejects_what_the_constructor_would():
    rng = np.random.default_rng(4)
    task, q_l, q_f, sigma = make_task(rng, PlaneBar())
    opts = StepOptions(dt=0.01, joint_weights=np.ones(6), grasp_weight=1.0)
    state = DualArmState(0.0, q_l, q_f, sigma)
    with pytest.raises(NonFiniteError):
        build(task, state, np.full(6, np.nan), opts)
    with pytest.raises(ShapeError):
        build(task, state, np.zeros(6), opts, x_prev=np.zeros(3))
    as_list = build(task, state, np.zeros(6), opts, x_prev=[0.0] * 7).problem
    assert as_list.x_prev is not None and as_list.x_prev.dtype == np.float64


def _rate_bounds_vectorised(x, x_min, x_max, v_max, dt, recovery_fraction):
    """The former numpy implementation of rate_bounds, kept as the reference."""
    lo = (x_min - x) / dt
    hi = (x_max - x) / dt
    with np.errstate(invalid="ignore"):
        center = np.where(np.isfinite(lo) & np.isfinite(hi), 0.5 * (lo + hi), 0.0)
    lower = np.maximum(lo, -v_max)
    upper = np.minimum(hi, v_max)
    below, above = lo > 0.0, hi < 0.0
    rec = recovery_fraction * v_max if recovery_fraction > 0 else np.zeros_like(v_max)
    lower = np.where(below, np.minimum(lo, rec), lower)
    upper = np.where(above, np.maximum(hi, -rec), upper)
    return lower, upper, center, below | above


@pytest.mark.parametrize("seed", range(5))
def test_rate_bounds_match_the_vectorised_formula(seed):
    rng = np.random.default_rng(seed)
    n = 9
    x = rng.normal(size=n) * 2.0
    x_min = np.where(rng.random(n) < 0.2, -np.inf, rng.normal(size=n) - 1.0)
    x_max = np.where(rng.random(n) < 0.2, np.inf, rng.normal(size=n) + 1.0)
    v_max = np.where(rng.random(n) < 0.3, np.inf, rng.uniform(0.5, 3.0, n))
    for fraction in (0.0, 0.5):
        got = rate_bounds(x, x_min, x_max, v_max, 0.05, fraction)
        want = _rate_bounds_vectorised(x, x_min, x_max, v_max, 0.05, fraction)
        for g, w in zip(got, want, strict=True):
            assert g.shape == w.shape and g.dtype == w.dtype
            np.testing.assert_array_equal(g, w)


def test_row_helpers_match_numpy():
    rng = np.random.default_rng(8)
    for _ in range(50):
        T1 = pin.SE3(pin.exp3(rng.normal(size=3) * 2), rng.normal(size=3)).homogeneous
        T2 = pin.SE3(pin.exp3(rng.normal(size=3) * 2), rng.normal(size=3)).homogeneous
        np.testing.assert_allclose(compose_rows(T1.tolist(), T2.tolist()), (T1 @ T2)[:3],
                                   atol=1e-15)
        np.testing.assert_allclose(pose_error_rows(T1.tolist(), T2.tolist()),
                                   pose_error(T1, T2), atol=1e-15)
