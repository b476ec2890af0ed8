"""Quasi-static joint torques and their derivatives, checked against finite differences.

Every Jacobian here is compared with central differences of the function it
differentiates: the arm's ``d tau / d q`` at a fixed world wrench, and the whole
``d tau / d (q_l, q_f, sigma[, sigma_l])`` with the load split recomputed at every
neighbouring state (the split over the leader's joints by the rotation identity, over
the grasps by differences of the projector form, and for a support by differences of
the full split).
"""

from __future__ import annotations

import dataclasses
import pickle
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
import pytest
import yaml

from dualarm_qp.errors import InvalidInputError
from dualarm_qp.experiments import build_experiment, parse_config
from dualarm_qp.kinematics.puma560 import puma560
from dualarm_qp.kinematics.robots import example_robot_arm, example_robots_dir
from dualarm_qp.task.hands import hand_statics
from dualarm_qp.task.loads import split_load
from dualarm_qp.task.torques import ArmStatics, LoadTorques, split_operator, torque_limits_of

CONFIGS = Path(__file__).resolve().parents[2] / "configs"

#: Configs with a load added (name: mass [kg], mass centre [mm]); the UR5 ones need
#: example-robot-data.
CASES = {"puma_beam_limits": (6.0, [0.0, 0.0, 250.0]),
         "ur5_pair_sliding_bar": (8.0, [0.0, 0.0, 350.0]),
         "both_sliding_bar": (4.0, [0.0, 0.0, 400.0]),
         "curved_bar_waypoints": (5.0, [0.0, 0.0, 200.0]),
         "puma_beam_support": (None, None)}


def _experiment(name: str) -> Any:
    if name.startswith(("ur5", "both")) and example_robots_dir() is None:
        pytest.skip("example-robot-data is not installed")
    data = yaml.safe_load((CONFIGS / f"{name}.yaml").read_text())
    mass, centre = CASES[name]
    if mass is not None:
        data["object"].update(mass=mass, mass_centre=centre)
    return build_experiment(parse_config(data), name)


def _central(f: Any, y: np.ndarray, h: float = 1e-6) -> np.ndarray:
    cols = []
    for e in np.eye(y.size):
        cols.append((f(y + h * e) - f(y - h * e)) / (2.0 * h))
    return np.column_stack(cols)


@pytest.mark.parametrize("which", ["puma", "ur5"])
def test_arm_derivative_at_a_fixed_world_wrench(which: str) -> None:
    if which == "ur5":
        if example_robots_dir() is None:
            pytest.skip("example-robot-data is not installed")
        arm = example_robot_arm("ur5", "base_link", "tool0")
    else:
        arm = puma560(base=pin.SE3(pin.rpy.rpyToMatrix(0.2, -0.1, 0.4),
                                   np.array([0.1, 0.2, 0.3])).homogeneous)
    statics = ArmStatics(arm, np.array([0.0, 0.0, -9.81]))
    rng = np.random.default_rng(5)
    for _ in range(5):
        q = rng.uniform(-2.0, 2.0, arm.n)
        w = rng.normal(0.0, 20.0, 6)
        tau, dtau, J = statics.linearised(q, w)
        np.testing.assert_allclose(tau, statics.torque(q, w), atol=1e-12)
        fd = _central(lambda x, w=w: statics.torque(x, w), q)
        assert np.abs(dtau - fd).max() < 1e-6 * max(1.0, np.abs(fd).max())
        # tau = g + J^T w: the wrench's part is J^T w at the tool point.
        g = statics.torque(q, np.zeros(6))
        np.testing.assert_allclose(tau - g, J.T @ w, atol=1e-10)
        np.testing.assert_allclose(J, arm.jacobian(q), atol=1e-12)
        # The force at a point fixed in the world (a grasp point 5 cm off the tool point):
        # the moment moved to the tool point, and its derivative with the point held.
        point = arm.fk(q)[:3, 3] + rng.normal(0.0, 0.05, 3)
        tau, dtau, J = statics.linearised(q, w, point)
        np.testing.assert_allclose(tau, statics.torque(q, w, point), atol=1e-12)
        moved = np.r_[w[:3], w[3:] + np.cross(point - arm.fk(q)[:3, 3], w[:3])]
        np.testing.assert_allclose(tau - g, J.T @ moved, atol=1e-10)
        fd = _central(lambda x, w=w, c=point: statics.torque(x, w, c), q)
        assert np.abs(dtau - fd).max() < 1e-6 * max(1.0, np.abs(fd).max())


@pytest.mark.parametrize("which", ["puma", "ur5"])
def test_compiled_gravity_is_pinocchios(which: str) -> None:
    """The kernel's statics (its copy of the model, inertias and gravity) against
    Pinocchio's Python ``computeGeneralizedGravity`` on the arm's own model."""
    if which == "ur5":
        if example_robots_dir() is None:
            pytest.skip("example-robot-data is not installed")
        arm = example_robot_arm("ur5", "base_link", "tool0")
    else:
        arm = puma560()
    gravity = np.array([0.3, -0.2, -9.81])
    statics = ArmStatics(arm, gravity)
    model = pin.Model(arm.model)
    model.gravity = pin.Motion(gravity, np.zeros(3))
    data = model.createData()
    rng = np.random.default_rng(9)
    tool = arm.tool_frame_id
    joint = model.frames[tool].parentJoint
    for _ in range(5):
        q = rng.uniform(-2.0, 2.0, arm.n)
        expected = pin.computeGeneralizedGravity(model, data, q)
        assert np.abs(expected).max() > 1.0
        np.testing.assert_allclose(statics.torque(q, np.zeros(6)), expected, rtol=0.0,
                                   atol=1e-12 * max(1.0, np.abs(expected).max()))
        # With a wrench: -w on the hand, about the tool point, world axes.
        w = rng.normal(0.0, 20.0, 6)
        pin.forwardKinematics(model, data, q)
        p = pin.updateFramePlacement(model, data, tool).translation
        fext = pin.StdVec_Force()
        for _ in range(model.njoints):
            fext.append(pin.Force.Zero())
        fext[joint] = data.oMi[joint].actInv(pin.Force(-w[:3], -w[3:] + np.cross(p, -w[:3])))
        loaded = pin.computeStaticTorque(model, data, q, fext)
        np.testing.assert_allclose(statics.torque(q, w), loaded, rtol=0.0,
                                   atol=1e-12 * max(1.0, np.abs(loaded).max()))
        # The force at a world point c, its moment about c.
        c = p + rng.normal(0.0, 0.05, 3)
        fext[joint] = data.oMi[joint].actInv(pin.Force(-w[:3], -w[3:] + np.cross(c, -w[:3])))
        loaded = pin.computeStaticTorque(model, data, q, fext)
        np.testing.assert_allclose(statics.torque(q, w, c), loaded, rtol=0.0,
                                   atol=1e-12 * max(1.0, np.abs(loaded).max()))


def test_load_torques_pickle() -> None:
    """The statics' compiled chains are rebuilt on unpickling (a sweep's workers), from
    the model they were made of: a later edit of the arm's own model does not reach
    them."""
    exp = _experiment("puma_beam_limits")
    torques = LoadTorques(exp.task)
    copy = pickle.loads(pickle.dumps(torques))
    s = exp.initial
    first = torques.linearised(s.q_l, s.q_f, s.sigma)
    again = copy.linearised(s.q_l, s.q_f, s.sigma)
    np.testing.assert_array_equal(first.tau, again.tau)
    np.testing.assert_array_equal(first.D, again.D)
    arm = exp.task.leader
    statics = ArmStatics(arm, np.array([0.0, 0.0, -9.81]))
    q = s.q_l + 0.3
    before = statics.torque(q, np.zeros(6))
    kept = arm.model.jointPlacements[1]
    arm.model.jointPlacements[1] = pin.SE3(pin.rpy.rpyToMatrix(0.3, 0.2, 0.1),
                                           kept.translation)
    try:
        copied = pickle.loads(pickle.dumps(statics))
    finally:
        arm.model.jointPlacements[1] = kept
    np.testing.assert_array_equal(statics.torque(q, np.zeros(6)), before)
    np.testing.assert_array_equal(copied.torque(q, np.zeros(6)), before)


@pytest.mark.parametrize("name", sorted(CASES))
def test_whole_derivative_matches_finite_differences(name: str) -> None:
    exp = _experiment(name)
    torques = LoadTorques(exp.task)
    s = exp.initial
    n_l, n_f, n_g = exp.task.leader.n, exp.task.follower.n, torques.n_grasp
    rng = np.random.default_rng(11)
    for trial in range(1 if name == "both_sliding_bar" else 3):
        q_l = s.q_l + (0.0 if trial == 0 else rng.normal(0.0, 0.03, n_l))
        q_f = s.q_f + (0.0 if trial == 0 else rng.normal(0.0, 0.03, n_f))
        y = np.r_[q_l, q_f, s.sigma, s.sigma_leader][:n_l + n_f + n_g]

        def tau(y: np.ndarray) -> np.ndarray:
            sigma_l = float(y[n_l + n_f + 1]) if n_g == 2 else 0.0
            q_l, q_f, sigma = y[:n_l], y[n_l:n_l + n_f], float(y[n_l + n_f])
            if name != "both_sliding_bar":
                return torques.torques(q_l, q_f, sigma, sigma_l)
            # Two slides along one axis hold the bar only level: next to it the split
            # is the least-squares one (the full split refuses the tilt).
            hands, T = hand_statics(exp.task, q_l, sigma, sigma_l)
            load = exp.task.load
            K = split_operator(hands, T[:3, :3] @ load.mass_centre + T[:3, 3], load.mass)
            w = (K @ load.gravity).reshape(2, 6)
            return np.r_[torques.leader.torque(q_l, w[0], hands[0].point),
                         torques.follower.torque(q_f, w[1], hands[1].point)]

        st = torques.linearised(q_l, q_f, s.sigma, s.sigma_leader)
        np.testing.assert_allclose(st.tau, tau(y), atol=1e-9)
        fd = _central(tau, y)
        scale = max(1.0, float(np.abs(fd).max()))
        assert np.abs(st.D - fd).max() < 1e-6 * scale, (name, np.abs(st.D - fd).max())
        # The grasp columns are not zero: where the grasp is moves the load.
        assert np.abs(fd[:, n_l + n_f:]).max() > 1e-3


@pytest.mark.parametrize("name", ["ur5_pair_sliding_bar", "both_sliding_bar",
                                  "puma_beam_limits"])
def test_split_operator_is_the_minimum_norm_split(name: str) -> None:
    exp = _experiment(name)
    task, s, load = exp.task, exp.initial, exp.task.load
    hands, T = hand_statics(task, s.q_l, s.sigma, s.sigma_leader)
    K = split_operator(hands, T[:3, :3] @ load.mass_centre + T[:3, 3], load.mass)
    assert K is not None
    np.testing.assert_allclose((K @ load.gravity).reshape(2, 6),
                               split_load(hands, load, T).wrenches, atol=1e-9)


def test_a_support_has_no_operator() -> None:
    exp = _experiment("puma_beam_support")
    task, s = exp.task, exp.initial
    hands, T = hand_statics(task, s.q_l, s.sigma)
    assert split_operator(hands, T[:3, 3], 1.0) is None


def test_torque_limits_default_to_the_urdf_effort() -> None:
    if example_robots_dir() is None:
        pytest.skip("example-robot-data is not installed")
    arm = example_robot_arm("ur5", "base_link", "tool0")
    np.testing.assert_array_equal(torque_limits_of(arm, None, "leader"),
                                  [150, 150, 150, 28, 28, 28])
    given = np.array([1.0, 2.0, 3.0, 4.0, 5.0, np.inf])
    np.testing.assert_array_equal(torque_limits_of(arm, given, "leader"), given)


@pytest.mark.parametrize("given, match", [
    (None, "states no joint torque limits"),
    (np.ones(5), "needs 6 values"),
    (np.array([1.0, 1.0, 0.0, 1.0, 1.0, 1.0]), "joint 3"),
    (np.array([1.0, np.nan, 1.0, 1.0, 1.0, 1.0]), "joint 2"),
])
def test_torque_limits_refused(given: Any, match: str) -> None:
    with pytest.raises(InvalidInputError, match=match):
        torque_limits_of(puma560(), given, "leader")


def test_load_torques_kernel_refuses_malformed_sets() -> None:
    """The kernel's call takes the state and one set of hands per sliding grasp."""
    from dualarm_qp._compiled import kernel
    from dualarm_qp.task.loads import FALLBACK_LENGTH
    from dualarm_qp.task.torques import GRASP_STEP, RCOND_MIN

    exp = _experiment("puma_beam_limits")
    torques = LoadTorques(exp.task)
    s = exp.initial
    load = exp.task.load
    hands, T = hand_statics(exp.task, s.q_l, s.sigma)
    points = np.array([h.point for h in hands])
    free = [h.free for h in hands]
    centre = T[:3, :3] @ load.mass_centre + T[:3, 3]
    args = (torques.leader.chain, torques.leader.frame, torques.follower.chain,
            torques.follower.frame, s.q_l, s.q_f, load.gravity, load.mass)
    tail = (GRASP_STEP, FALLBACK_LENGTH, RCOND_MIN)
    loads = kernel.load_torques(*args, [points] * 2, [free] * 2, [centre] * 2, *tail)
    tau, w = loads.tau, loads.w
    np.testing.assert_allclose(tau, torques.torques(s.q_l, s.q_f, s.sigma), atol=1e-9)
    np.testing.assert_allclose(w, torques.wrenches(s.q_l, s.sigma), atol=1e-9)
    with pytest.raises(ValueError, match="one set per sliding grasp"):
        kernel.load_torques(*args, [points], [free], [centre], *tail)
    with pytest.raises(ValueError, match=r"\(2, 3\)"):
        kernel.load_torques(*args, [points[:1]] * 2, [free] * 2, [centre] * 2, *tail)
    with pytest.raises(ValueError, match="one entry per set"):
        kernel.load_torques(*args, [points] * 2, [free], [centre] * 2, *tail)
    with pytest.raises(ValueError, match="grasp_step"):
        kernel.load_torques(*args, [points] * 2, [free] * 2, [centre] * 2, 0.0, *tail[1:])
    with pytest.raises(ValueError, match="gravity"):
        kernel.load_torques(*args[:6], 2.0 * load.gravity, load.mass, [points] * 2,
                            [free] * 2, [centre] * 2, *tail)


def test_split_operator_refuses_degenerate_hands() -> None:
    """Dependent free twists or NaN: an error, not a NaN split."""
    from dualarm_qp.task.loads import rigid_grasp, sliding_grasp

    rigid = rigid_grasp([0.0, 0.0, 0.0])
    slide = sliding_grasp([1.0, 0.0, 0.0], [1.0, 0.0, 0.0])
    K = split_operator([rigid, slide], np.array([0.5, 0.0, 0.0]), 2.0)
    assert K is not None and np.isfinite(K).all()
    twice = dataclasses.replace(slide, free=np.column_stack([slide.free, slide.free[:, :1]]))
    with pytest.raises(ValueError, match="not independent"):
        split_operator([rigid, twice], np.array([0.5, 0.0, 0.0]), 2.0)
    with pytest.raises(ValueError, match="finite"):
        split_operator([rigid, slide], np.array([np.nan, 0.0, 0.0]), 2.0)
