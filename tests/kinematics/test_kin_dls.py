"""Damped-least-squares inverse kinematics (any DH arm)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from dualarm_qp.errors import IKError, InvalidInputError
from dualarm_qp.kinematics import DHTable, IKResult, SerialArm, ik_dls, puma560
from dualarm_qp.se3 import pose_error


def random_pose(rng: np.random.Generator, scale: float = 1.0) -> np.ndarray:
    return pin.SE3(pin.exp3(rng.normal(size=3)), scale * rng.normal(size=3)).homogeneous


def interior(arm: SerialArm, rng: np.random.Generator, margin: float = 0.2) -> np.ndarray:
    return rng.uniform(arm.q_min + margin, arm.q_max - margin)


def assert_solved(arm: SerialArm, res: IKResult, T: np.ndarray) -> None:
    assert res.success
    e = pose_error(T, arm.fk(res.q))
    assert np.linalg.norm(e[:3]) <= 1e-10 and np.linalg.norm(e[3:]) <= 1e-10
    assert res.position_error == pytest.approx(np.linalg.norm(e[:3]), abs=1e-15)
    assert arm.within_limits(res.q)


def test_converges_from_perturbed_starts_puma() -> None:
    rng = np.random.default_rng(0)
    arm = puma560(base=random_pose(rng), tool=random_pose(rng, 0.1))
    for _ in range(100):
        q = interior(arm, rng)
        T = arm.fk(q)
        res = ik_dls(arm, T, q + rng.normal(scale=0.1, size=6))
        assert_solved(arm, res, T)
        assert res.iterations <= 15


def test_converges_for_redundant_modified_dh_arm() -> None:
    rng = np.random.default_rng(1)
    rows = np.column_stack([rng.uniform(0.1, 0.4, 7), rng.choice([-np.pi / 2, np.pi / 2], 7),
                            rng.uniform(0.0, 0.2, 7)])
    arm = SerialArm(DHTable.from_rows(rows, "modified"), q_min=-2.5, q_max=2.5)
    for _ in range(30):
        q = interior(arm, rng)
        T = arm.fk(q)
        assert_solved(arm, ik_dls(arm, T, q + rng.normal(scale=0.2, size=7)), T)


def test_quadratic_convergence_near_a_solution() -> None:
    """The drift-correction use: from 1e-3 rad away, at most three iterations reach
    1e-10, and each iteration squares the error (up to a constant)."""
    rng = np.random.default_rng(2)
    arm = puma560()
    for _ in range(50):
        q = interior(arm, rng)
        T = arm.fk(q)
        q0 = q + rng.normal(scale=1e-3, size=6)
        res = ik_dls(arm, T, q0)
        assert_solved(arm, res, T)
        assert res.iterations <= 3
        errors = [ik_dls(arm, T, q0, max_iter=k, raise_on_failure=False) for k in (0, 1)]
        e0, e1 = (r.position_error + r.rotation_error for r in errors)
        assert e1 <= 1e4 * e0**2
    assert ik_dls(arm, T, q).iterations == 0  # already solved: no linear solve at all


def test_unreachable_target_reports_failure() -> None:
    arm = puma560()
    q0 = np.zeros(6)
    far = pin.SE3(np.eye(3), np.array([3.0, 0.0, 0.5])).homogeneous
    with pytest.raises(IKError) as info:
        ik_dls(arm, far, q0)
    assert info.value.position_error > 2.0 and np.isfinite(info.value.rotation_error)
    res = ik_dls(arm, far, q0, raise_on_failure=False)
    assert not res.success and res.position_error == pytest.approx(info.value.position_error)
    assert res.iterations < 200  # stalls instead of burning every iteration
    assert arm.within_limits(res.q)


def test_limits_are_respected() -> None:
    arm = puma560()
    q_target = np.deg2rad([170.0, -30.0, 100.0, 0.0, 45.0, 0.0])  # joint 1 beyond 160 deg
    T = arm.fk(q_target)
    res = ik_dls(arm, T, np.deg2rad([150.0, -30.0, 100.0, 0.0, 45.0, 0.0]),
                 raise_on_failure=False)
    assert arm.within_limits(res.q)
    free = ik_dls(arm, T, np.deg2rad([150.0, -30.0, 100.0, 0.0, 45.0, 0.0]),
                  respect_limits=False)
    assert free.success


def test_start_outside_limits_is_clipped() -> None:
    arm = puma560()
    q = np.deg2rad([150.0, -30.0, 100.0, 0.0, 45.0, 0.0])
    res = ik_dls(arm, arm.fk(q), q + np.deg2rad([20.0, 0, 0, 0, 0, 0]))
    assert_solved(arm, res, arm.fk(q))


def test_max_iter_zero_only_checks() -> None:
    arm = puma560()
    q = np.full(6, 0.3)
    assert ik_dls(arm, arm.fk(q), q, max_iter=0).success
    with pytest.raises(IKError, match="0 iterations"):
        ik_dls(arm, arm.fk(q), q + 0.1, max_iter=0)


def test_bad_options() -> None:
    arm = puma560()
    T = arm.fk(np.zeros(6))
    for kwargs in ({"damping": 0.0}, {"tol_pos": -1.0}, {"max_iter": -1}, {"max_iter": 1.5}):
        with pytest.raises(InvalidInputError):
            ik_dls(arm, T, np.zeros(6), **kwargs)
    with pytest.raises(InvalidInputError):
        ik_dls(arm, T, np.zeros(5))
    with pytest.raises(InvalidInputError):
        ik_dls(arm, pin.SE3(2 * np.eye(3), np.zeros(3)).homogeneous, np.zeros(6))


def _oracle_dls(arm: SerialArm, T: np.ndarray, q0: np.ndarray, tol: float, max_iter: int,
                lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, bool, int]:
    """The method of the module docstring in plain numpy: an independent implementation.

    Pose errors by Pinocchio's Python ``log3``, the kinematics by the arm's ``fk`` and
    ``jacobian``, the solve by numpy's LAPACK.
    """
    def error(q: np.ndarray) -> tuple[np.ndarray, float, float]:
        A = arm.fk(q)
        e = np.concatenate([T[:3, 3] - A[:3, 3], pin.log3(T[:3, :3] @ A[:3, :3].T)])
        return e, float(np.linalg.norm(e[:3])), float(np.linalg.norm(e[3:]))

    q = np.clip(q0, lo, hi)
    e, ep, er = error(q)
    J, mu, k = arm.jacobian(q), 1e-2, 0
    while not (ep <= tol and er <= tol) and k < max_iter:
        k += 1
        g = J.T @ e
        free = ~(((q <= lo) & (g < 0.0)) | ((q >= hi) & (g > 0.0)))
        Jf = J[:, free]
        dq = np.zeros(arm.n)
        cost = ep * ep + er * er
        dq[free] = np.linalg.solve(Jf.T @ Jf + mu * cost * np.eye(int(free.sum())), g[free])
        q_new = np.clip(q + dq, lo, hi)
        if np.abs(q_new - q).max() <= 1e-15 * (1.0 + np.abs(q).max()):
            break
        e_new, ep_new, er_new = error(q_new)
        if ep_new**2 + er_new**2 < cost:
            Js = J @ (q_new - q)
            predicted = 2.0 * e @ Js - Js @ Js
            rho = (cost - ep_new**2 - er_new**2) / predicted if predicted > 0.0 else 0.0
            mu = max(mu / 3.0, 1e-12) if rho > 0.75 else min(mu * 2.0, 1e16) if rho < 0.25 else mu
            q, e, ep, er, J = q_new, e_new, ep_new, er_new, arm.jacobian(q_new)
        else:
            mu *= 10.0
            if mu > 1e16:
                break
    return q, bool(ep <= tol and er <= tol), k


@pytest.mark.parametrize("limits", [True, False])
def test_the_kernel_iterates_as_the_method_states(limits: bool) -> None:
    """The compiled iterations against a plain numpy implementation of the same method.

    From near and far starts, to targets inside the ranges and (with the ranges kept)
    beyond them, where joints rest on their limits and are frozen and the solve fails
    at the closest point it can reach. Only rounding differs: both succeed or fail
    together at the same joints; a success takes the same number of iterations (save a
    few cases where rounding decides the way); a failure creeps to its point in a number
    of iterations that rounding moves by a few, the same in total.
    """
    rng = np.random.default_rng(7)
    arm = puma560(base=random_pose(rng), tool=random_pose(rng, 0.1))
    inf = np.full(6, np.inf)
    lo, hi = (arm.q_min, arm.q_max) if limits else (-inf, inf)
    counted, differ, failed, failed_ref, frozen = 0, 0, 0, 0, 0
    for k in range(90):
        q = interior(arm, rng)
        if limits and k % 2:  # a target beyond a joint's range: that joint ends on it
            i = int(rng.integers(6))
            q[i] = arm.q_max[i] + 0.2 if k % 4 == 1 else arm.q_min[i] - 0.2
        T = arm.fk(q)
        q0 = q + rng.normal(scale=(0.02, 0.2, 0.6)[k % 3], size=6)
        res = ik_dls(arm, T, q0, tol_pos=1e-10, tol_rot=1e-10, respect_limits=limits,
                     raise_on_failure=False)
        q_ref, ok_ref, k_ref = _oracle_dls(arm, T, q0, 1e-10, 200, lo, hi)
        assert res.success == ok_ref
        np.testing.assert_allclose(res.q, q_ref, rtol=0, atol=1e-7)
        if ok_ref:
            counted += 1
            differ += res.iterations != k_ref
        else:
            failed += res.iterations
            failed_ref += k_ref
            frozen += bool(np.any((res.q == lo) | (res.q == hi)))
    assert counted >= 40 and differ <= 3
    assert abs(failed - failed_ref) <= 0.1 * failed_ref
    assert frozen >= (40 if limits else 0)


def test_a_large_iteration_budget_is_taken() -> None:
    arm = puma560()
    q = np.full(6, 0.3)
    res = ik_dls(arm, arm.fk(q), q + 0.05, max_iter=2**40)
    assert res.success and res.iterations < 20
    assert ik_dls(arm, arm.fk(q), q + 0.05, max_iter=10**30).success


def test_a_joint_resting_on_a_limit_that_the_error_pushes_past_stays_there() -> None:
    """The frozen joint: the target lies beyond joint 1's upper limit, the start on it."""
    arm = puma560()
    q_start = np.deg2rad([160.0, -30.0, 100.0, 0.0, 45.0, 0.0])  # joint 1 at its limit
    T = arm.fk(np.deg2rad([175.0, -30.0, 100.0, 0.0, 45.0, 0.0]))
    for max_iter in (1, 2, 5, 200):
        res = ik_dls(arm, T, q_start, max_iter=max_iter, raise_on_failure=False)
        assert res.q[0] == arm.q_max[0]  # never past it, never pulled off it
        assert arm.within_limits(res.q)
    assert not res.success
