"""Desired object trajectories D(t): exact twists against finite differences, waypoints."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dualarm_qp._compiled import kernel
from dualarm_qp.errors import InvalidInputError, NonFiniteError, ShapeError
from dualarm_qp.task import (
    PAPER_R0,
    LinearTrajectory,
    Trajectory,
    WaypointTrajectory,
    min_jerk,
    paper_trajectory,
)

H = 1e-6


def fd_twist(traj: Trajectory, t: float, h: float = H) -> np.ndarray:
    Tp, Tm = traj.pose(t + h), traj.pose(t - h)
    out = np.empty(6)
    out[:3] = (Tp[:3, 3] - Tm[:3, 3]) / (2 * h)
    out[3:] = pin.log3(Tp[:3, :3] @ Tm[:3, :3].T) / (2 * h)
    return out


def fd_acceleration(traj: Trajectory, t: float, h: float = 1e-5) -> np.ndarray:
    return (traj.twist(t + h) - traj.twist(t - h)) / (2 * h)


# --- LinearTrajectory ----------------------------------------------------------------------


def test_paper_trajectory_values() -> None:
    traj = paper_trajectory(duration=2.0)
    # D(t) of Section 4: d_x(t) = t/31 - 0.3 [mm, t in ms].
    for t_ms in (0.0, 31.0, 620.0, 1550.0):
        T = traj.pose(t_ms / 1000.0)
        np.testing.assert_allclose(
            T[:3, 3], np.array([t_ms / 31.0 - 0.3, 690.0, 260.4]) / 1000.0, atol=1e-15
        )
        np.testing.assert_array_equal(T[:3, :3], PAPER_R0)
    np.testing.assert_allclose(traj.twist(0.5), [0.0322580645, 0, 0, 0, 0, 0], atol=1e-10)
    assert (traj.t0, traj.tf, traj.duration) == (0.0, 2.0, 2.0)


def test_linear_twist_matches_finite_differences() -> None:
    traj = LinearTrajectory([0.1, -0.2, 0.3], [0.05, -0.01, 0.02],
                            R0=pin.rpy.rpyToMatrix(0.0, 0.0, 0.4), tf=3.0)
    for t in (0.1, 1.0, 2.9):
        np.testing.assert_allclose(traj.twist(t), fd_twist(traj, t), atol=1e-9)
        np.testing.assert_array_equal(traj.acceleration(t), np.zeros(6))


def test_linear_clamps_outside_interval() -> None:
    traj = LinearTrajectory([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], t0=1.0, tf=2.0)
    np.testing.assert_array_equal(traj.pose(0.0), traj.pose(1.0))
    np.testing.assert_array_equal(traj.pose(5.0), traj.pose(2.0))
    assert traj.pose(5.0)[0, 3] == 1.0
    np.testing.assert_array_equal(traj.twist(0.5), np.zeros(6))
    np.testing.assert_array_equal(traj.twist(2.5), np.zeros(6))
    np.testing.assert_array_equal(traj.twist(2.0), [1, 0, 0, 0, 0, 0])  # closed interval
    # Returned arrays are fresh: mutating them does not change the trajectory.
    traj.pose(1.5)[0, 3] = 99.0
    traj.twist(1.5)[0] = 99.0
    assert traj.pose(1.5)[0, 3] == 0.5 and traj.twist(1.5)[0] == 1.0


def test_linear_bad_inputs() -> None:
    with pytest.raises(InvalidInputError, match="tf"):
        LinearTrajectory([0, 0, 0], [1, 0, 0], tf=0.0)
    with pytest.raises(ShapeError):
        LinearTrajectory([0, 0], [1, 0, 0], tf=1.0)
    with pytest.raises(NonFiniteError):
        LinearTrajectory([0, 0, math.nan], [1, 0, 0], tf=1.0)
    with pytest.raises(InvalidInputError, match="proper rotation"):
        LinearTrajectory([0, 0, 0], [1, 0, 0], R0=np.diag([1.0, 1.0, -1.0]), tf=1.0)
    with pytest.raises(NonFiniteError):
        paper_trajectory(duration=math.inf)
    traj = paper_trajectory(duration=1.0)
    with pytest.raises(NonFiniteError):
        traj.pose(math.nan)
    with pytest.raises(NonFiniteError):
        traj.twist(math.nan)


# --- WaypointTrajectory --------------------------------------------------------------------


def test_min_jerk_boundary_conditions() -> None:
    assert min_jerk(0.0) == (0.0, 0.0, 0.0)
    s, ds, dds = min_jerk(1.0)
    assert (s, ds, dds) == pytest.approx((1.0, 0.0, 0.0), abs=1e-12)
    for tau in (0.1, 0.5, 0.8):
        h = 1e-6
        assert min_jerk(tau)[1] == pytest.approx(
            (min_jerk(tau + h)[0] - min_jerk(tau - h)[0]) / (2 * h), abs=1e-8
        )
        assert min_jerk(tau)[2] == pytest.approx(
            (min_jerk(tau + h)[1] - min_jerk(tau - h)[1]) / (2 * h), abs=1e-7
        )


def _three_waypoints() -> WaypointTrajectory:
    poses = [
        pin.SE3(np.eye(3), np.array([0.0, 0.0, 0.0])).homogeneous,
        pin.SE3(pin.rpy.rpyToMatrix(0.5, 0.0, 1.0), np.array([0.3, -0.1, 0.2])).homogeneous,
        pin.SE3(pin.rpy.rpyToMatrix(-2.5, 0.0, 0.0), np.array([0.1, 0.4, 0.0])).homogeneous,
    ]
    return WaypointTrajectory([0.5, 1.5, 3.5], poses)


def test_waypoints_are_reached_at_rest() -> None:
    traj = _three_waypoints()
    for tk, Tk in zip(traj.times, traj.waypoints, strict=True):
        np.testing.assert_allclose(traj.pose(tk), Tk, atol=1e-12)
        np.testing.assert_allclose(traj.twist(tk), np.zeros(6), atol=1e-12)
        np.testing.assert_allclose(traj.acceleration(tk), np.zeros(6), atol=1e-12)
        # Continuous across the waypoint.
        np.testing.assert_allclose(traj.pose(tk - 1e-9), traj.pose(tk + 1e-9), atol=1e-8)


def test_waypoint_twist_and_acceleration_match_finite_differences() -> None:
    traj = _three_waypoints()
    for t in np.linspace(0.51, 3.49, 23):
        np.testing.assert_allclose(traj.twist(t), fd_twist(traj, t), atol=1e-7)
        np.testing.assert_allclose(traj.acceleration(t), fd_acceleration(traj, t), atol=1e-6)


def test_waypoint_clamps_outside_interval() -> None:
    traj = _three_waypoints()
    np.testing.assert_allclose(traj.pose(-1.0), traj.waypoints[0])
    np.testing.assert_allclose(traj.pose(10.0), traj.waypoints[-1])
    np.testing.assert_array_equal(traj.twist(10.0), np.zeros(6))
    np.testing.assert_array_equal(traj.acceleration(-1.0), np.zeros(6))


rotvec = st.tuples(*[st.floats(-2.0, 2.0)] * 3)
position = st.tuples(*[st.floats(-1.0, 1.0)] * 3)


@settings(max_examples=60, deadline=None)
@given(
    w=st.lists(rotvec, min_size=2, max_size=4),
    p=st.lists(position, min_size=4, max_size=4),
    dts=st.lists(st.floats(0.05, 3.0), min_size=3, max_size=3),
    frac=st.floats(0.02, 0.98),
)
def test_waypoint_properties(
    w: list[tuple[float, float, float]],
    p: list[tuple[float, float, float]],
    dts: list[float],
    frac: float,
) -> None:
    n = len(w)
    poses = [pin.SE3(pin.exp3(np.array(w[i])), np.array(p[i])).homogeneous for i in range(n)]
    times = np.concatenate([[0.0], np.cumsum(dts[: n - 1])])
    traj = WaypointTrajectory(times, poses)
    for k in range(n):
        np.testing.assert_allclose(traj.pose(times[k]), poses[k], atol=1e-9)
        np.testing.assert_allclose(traj.twist(times[k]), 0.0, atol=1e-9)
    t = frac * traj.tf
    T = traj.pose(t)
    np.testing.assert_allclose(T[:3, :3].T @ T[:3, :3], np.eye(3), atol=1e-12)
    h = 1e-6 * min(dts)
    np.testing.assert_allclose(traj.twist(t), fd_twist(traj, t, h), atol=2e-5, rtol=1e-5)


@settings(max_examples=40, deadline=None)
@given(w=st.lists(st.tuples(*[st.floats(-0.5, 0.5)] * 3), min_size=2, max_size=4),
       p=st.lists(position, min_size=4, max_size=4),
       dts=st.lists(st.floats(0.05, 3.0), min_size=3, max_size=3),
       fracs=st.lists(st.floats(-0.2, 1.2), min_size=5, max_size=5))
def test_the_compiled_path_is_its_formula(
    w: list[tuple[float, float, float]],
    p: list[tuple[float, float, float]],
    dts: list[float],
    fracs: list[float],
) -> None:
    """The kernel's path against the class docstring's formula, written here in numpy:
    ``p_k + s dp`` and ``R_k exp(s w_k)`` with ``w_k = log(R_k^T R_k+1)``, their rates by
    ``s_dot`` and ``s_ddot``, the end waypoints outside (rotations well away from pi)."""
    n = len(w)
    poses = [pin.SE3(pin.exp3(np.array(w[i])), np.array(p[i])).homogeneous for i in range(n)]
    times = np.concatenate([[0.0], np.cumsum(dts[: n - 1])])
    traj = WaypointTrajectory(times, poses)
    for frac in fracs:
        t = frac * float(times[-1])
        if t <= times[0] or t >= times[-1]:
            end = poses[0] if t <= times[0] else poses[-1]
            np.testing.assert_allclose(traj.pose(t), end, rtol=0, atol=1e-15)
            continue
        k = int(np.searchsorted(times, t, side="right")) - 1
        span = times[k + 1] - times[k]
        tau = (t - times[k]) / span
        s = 10 * tau**3 - 15 * tau**4 + 6 * tau**5
        ds = (30 * tau**2 - 60 * tau**3 + 30 * tau**4) / span
        dds = (60 * tau - 180 * tau**2 + 120 * tau**3) / span**2
        Rk, dp = poses[k][:3, :3], poses[k + 1][:3, 3] - poses[k][:3, 3]
        wk = pin.log3(Rk.T @ poses[k + 1][:3, :3])
        T = traj.pose(t)
        np.testing.assert_allclose(T[:3, 3], poses[k][:3, 3] + s * dp, rtol=0, atol=1e-14)
        np.testing.assert_allclose(T[:3, :3], Rk @ pin.exp3(s * wk), rtol=0, atol=1e-14)
        np.testing.assert_array_equal(T[3], [0.0, 0.0, 0.0, 1.0])
        np.testing.assert_allclose(traj.twist(t), np.r_[ds * dp, ds * (Rk @ wk)],
                                   rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(traj.acceleration(t), np.r_[dds * dp, dds * (Rk @ wk)],
                                   rtol=1e-12, atol=1e-11)


def test_a_time_that_is_not_a_number_is_refused() -> None:
    """By the class (the library's error) and, under it, by the kernel's path itself."""
    traj = _three_waypoints()
    for f in (traj.pose, traj.twist, traj.acceleration):
        with pytest.raises(NonFiniteError):
            f(math.nan)
        with pytest.raises(NonFiniteError):  # an integer beyond the largest float
            f(10**400)
    path = kernel.WaypointPath([0.0, 1.0], np.concatenate([np.eye(4), np.eye(4)]))
    with pytest.raises(ValueError, match="NaN"):
        path.pose(math.nan, np.empty((4, 4)))
    with pytest.raises(ValueError, match="NaN"):
        path.derivative(math.nan, 1, np.empty(6))


def test_min_jerk_takes_arrays() -> None:
    tau = np.linspace(0.0, 1.0, 7)
    s, ds, dds = min_jerk(tau)
    for i, t in enumerate(tau.tolist()):
        assert (s[i], ds[i], dds[i]) == min_jerk(t)


def test_waypoints_too_close_in_time_are_refused() -> None:
    T = np.eye(4)
    with pytest.raises(InvalidInputError, match="at least 1e-09 s apart"):
        WaypointTrajectory([0.0, 1e-170, 1.0], [T, T, T])


def test_a_waypoint_path_survives_pickling_and_copying() -> None:
    import copy
    import pickle
    from pathlib import Path

    from dualarm_qp.experiments import build_experiment, load_config

    traj = _three_waypoints()
    for other in (pickle.loads(pickle.dumps(traj)), copy.deepcopy(traj)):
        for t in (0.2, 0.7, 1.5, 2.9, 4.0):
            np.testing.assert_array_equal(other.pose(t), traj.pose(t))
            np.testing.assert_array_equal(other.acceleration(t), traj.acceleration(t))
    path = Path(__file__).resolve().parents[2] / "configs" / "curved_bar_waypoints.yaml"
    exp = build_experiment(load_config(path), str(path))  # an experiment holding one
    again = pickle.loads(pickle.dumps(exp))
    np.testing.assert_array_equal(again.task.trajectory.pose(2.3), exp.task.trajectory.pose(2.3))


def test_waypoint_bad_inputs() -> None:
    T = np.eye(4)
    with pytest.raises(InvalidInputError, match="strictly increasing"):
        WaypointTrajectory([0.0, 1.0, 1.0], [T, T, T])
    with pytest.raises(InvalidInputError, match="at least two"):
        WaypointTrajectory([0.0], [T])
    with pytest.raises(ShapeError):
        WaypointTrajectory([0.0, 1.0], [T, T, T])
    with pytest.raises(ShapeError):
        WaypointTrajectory([[0.0, 1.0]], [T, T])
    with pytest.raises(NonFiniteError):
        WaypointTrajectory([0.0, math.nan], [T, T])
    bad = T.copy()
    bad[:3, :3] = np.diag([1.0, -1.0, 1.0])  # a reflection
    with pytest.raises(InvalidInputError, match="proper rotation"):
        WaypointTrajectory([0.0, 1.0], [T, bad])
    nan = T.copy()
    nan[0, 3] = math.nan
    with pytest.raises(NonFiniteError):
        WaypointTrajectory([0.0, 1.0], [T, nan])
    with pytest.raises(InvalidInputError):
        WaypointTrajectory([0.0, 1.0], "not poses")
    with pytest.raises(NonFiniteError):
        _three_waypoints().pose(math.nan)
