"""Forward kinematics and Jacobians of DH arms (both conventions) and of the PUMA 560.

The arms compute with Pinocchio; ``dh_oracle`` is an independent textbook DH chain.
"""

from __future__ import annotations

import dh_oracle
import numpy as np
import pinocchio as pin
import pytest
from fd import fd_jacobian
from hypothesis import given, settings
from hypothesis import strategies as st

from dualarm_qp.kinematics import DHTable, SerialArm, puma560
from dualarm_qp.kinematics.puma560 import PUMA560_A, PUMA560_ALPHA, PUMA560_D

SETTINGS = settings(max_examples=60, deadline=None)


def random_pose(rng: np.random.Generator, scale: float = 1.0) -> np.ndarray:
    return pin.SE3(pin.exp3(rng.normal(size=3)), scale * rng.normal(size=3)).homogeneous


def trans(x: float = 0.0, y: float = 0.0, z: float = 0.0) -> np.ndarray:
    return pin.SE3(np.eye(3), np.array([x, y, z])).homogeneous


def reference_fk(arm: SerialArm, rows: np.ndarray, q: np.ndarray) -> np.ndarray:
    return dh_oracle.fk(rows, q, arm.dh.convention, arm.base, arm.tool)


# Link twists: exact special values (handled by dedicated code paths) and generic ones.
alphas = st.one_of(
    st.sampled_from([0.0, np.pi / 2, -np.pi / 2, np.pi]),
    st.floats(-np.pi, np.pi, allow_nan=False),
)
lengths = st.one_of(st.just(0.0), st.floats(-1.0, 1.0, allow_nan=False))
rows_strategy = st.integers(1, 8).flatmap(
    lambda n: st.lists(st.tuples(lengths, alphas, lengths, st.floats(-np.pi, np.pi)),
                       min_size=n, max_size=n)
)


@st.composite
def dh_arms(draw: st.DrawFn) -> tuple[SerialArm, np.ndarray, np.ndarray]:
    rows = np.array(draw(rows_strategy), dtype=float)
    convention = draw(st.sampled_from(["standard", "modified"]))
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    base = random_pose(rng) if draw(st.booleans()) else None
    tool = random_pose(rng, 0.3) if draw(st.booleans()) else None
    arm = SerialArm(DHTable.from_rows(rows, convention), base=base, tool=tool)
    q = rng.uniform(-np.pi, np.pi, size=arm.n)
    return arm, rows, q


@SETTINGS
@given(dh_arms())
def test_fk_matches_textbook_formula(case: tuple[SerialArm, np.ndarray, np.ndarray]) -> None:
    arm, rows, q = case
    np.testing.assert_allclose(arm.fk(q), reference_fk(arm, rows, q), atol=1e-12)


@SETTINGS
@given(dh_arms())
def test_jacobian_and_frames_match_the_oracle(
    case: tuple[SerialArm, np.ndarray, np.ndarray],
) -> None:
    arm, rows, q = case
    convention = arm.dh.convention
    T, J = arm.fk_jacobian(q)
    np.testing.assert_allclose(T, dh_oracle.fk(rows, q, convention, arm.base, arm.tool),
                               rtol=0, atol=1e-12)
    np.testing.assert_allclose(J, dh_oracle.jacobian(rows, q, convention, arm.base, arm.tool),
                               rtol=0, atol=1e-12)
    np.testing.assert_allclose(arm.link_frames(q),
                               dh_oracle.frames(rows, q, convention, arm.base),
                               rtol=0, atol=1e-12)


def test_puma_matches_the_oracle_with_random_bases_and_tools() -> None:
    rows = np.column_stack([PUMA560_A, PUMA560_ALPHA, PUMA560_D, np.zeros(6)])
    rng = np.random.default_rng(11)
    for _ in range(200):
        base, tool = random_pose(rng), random_pose(rng, 0.2)
        arm = puma560(base=base, tool=tool)
        q = rng.uniform(arm.q_min, arm.q_max)
        T, J = arm.fk_jacobian(q)
        np.testing.assert_allclose(T, dh_oracle.fk(rows, q, "standard", base, tool),
                                   rtol=0, atol=1e-12)
        np.testing.assert_allclose(J, dh_oracle.jacobian(rows, q, "standard", base, tool),
                                   rtol=0, atol=1e-12)


def test_data_is_allocated_once_per_arm() -> None:
    arm = puma560()
    data = arm.data
    arm.fk_jacobian(np.zeros(6))
    arm.link_frames(np.ones(6))
    assert arm.data is data
    assert arm.with_base(random_pose(np.random.default_rng(0))).data is not data


@SETTINGS
@given(dh_arms())
def test_jacobian_matches_finite_differences(
    case: tuple[SerialArm, np.ndarray, np.ndarray],
) -> None:
    arm, _, q = case
    T, J = arm.fk_jacobian(q)
    np.testing.assert_allclose(T, arm.fk(q), atol=1e-14)
    np.testing.assert_allclose(J, arm.jacobian(q), atol=0)
    np.testing.assert_allclose(J, fd_jacobian(arm, q), atol=1e-7)
    assert J.shape == (6, arm.n) and J.flags.c_contiguous


@SETTINGS
@given(dh_arms())
def test_link_frames_end_at_fk(case: tuple[SerialArm, np.ndarray, np.ndarray]) -> None:
    arm, _, q = case
    F = arm.link_frames(q)
    assert F.shape == (arm.n + 1, 4, 4)
    np.testing.assert_allclose(F[0], arm.base, atol=0)
    np.testing.assert_allclose(F[-1] @ arm.tool, arm.fk(q), atol=1e-12)


@SETTINGS
@given(dh_arms())
def test_joint_axes_are_the_frame_z_axes(case: tuple[SerialArm, np.ndarray, np.ndarray]) -> None:
    """Standard DH: joint i turns about z of frame i-1; modified: about z of frame i."""
    arm, _, q = case
    F = arm.link_frames(q)
    axes = F[:-1] if arm.dh.convention == "standard" else F[1:]
    np.testing.assert_allclose(arm.jacobian(q)[3:], axes[:, :3, 2].T, atol=1e-12)


@SETTINGS
@given(rows_strategy, st.integers(0, 2**32 - 1))
def test_standard_equals_shifted_modified(rows: list, seed: int) -> None:
    """Standard Z1 X1 ... Zn Xn == modified X0 Z1 X1 ... Zn (X0 = I) with tool Xn."""
    rows_std = np.array(rows, dtype=float)
    rng = np.random.default_rng(seed)
    base = random_pose(rng)
    rows_mod = rows_std.copy()
    rows_mod[:, :2] = np.vstack([[0.0, 0.0], rows_std[:-1, :2]])
    a_n, alpha_n = rows_std[-1, :2]
    std = SerialArm(DHTable.from_rows(rows_std, "standard"), base=base)
    mod = SerialArm(DHTable.from_rows(rows_mod, "modified"), base=base,
                    tool=trans(x=a_n) @ pin.SE3(pin.rpy.rpyToMatrix(alpha_n, 0.0, 0.0),
                                                np.zeros(3)).homogeneous)
    q = rng.uniform(-np.pi, np.pi, size=std.n)
    T_s, J_s = std.fk_jacobian(q)
    T_m, J_m = mod.fk_jacobian(q)
    np.testing.assert_allclose(T_s, T_m, atol=1e-12)
    np.testing.assert_allclose(J_s, J_m, atol=1e-12)


def test_planar_arm_same_in_both_conventions() -> None:
    lengths = [0.5, 0.4, 0.3]
    std = SerialArm(DHTable.from_rows([[a, 0.0, 0.0] for a in lengths], "standard"))
    mod = SerialArm(DHTable.from_rows([[0.0, 0.0, 0.0], [0.5, 0.0, 0.0], [0.4, 0.0, 0.0]],
                                      "modified"), tool=trans(x=0.3))
    q = np.array([0.3, -1.1, 0.7])
    s1, s12, s123 = np.sin(q[0]), np.sin(q[:2].sum()), np.sin(q.sum())
    c1, c12, c123 = np.cos(q[0]), np.cos(q[:2].sum()), np.cos(q.sum())
    expected = np.array([0.5 * c1 + 0.4 * c12 + 0.3 * c123, 0.5 * s1 + 0.4 * s12 + 0.3 * s123, 0])
    for arm in (std, mod):
        np.testing.assert_allclose(arm.fk(q)[:3, 3], expected, atol=1e-14)
        np.testing.assert_allclose(arm.fk(q)[:3, :3], pin.rpy.rpyToMatrix(0.0, 0.0, q.sum()),
                                   atol=1e-14)
    np.testing.assert_allclose(std.jacobian(q), mod.jacobian(q), atol=1e-14)


def test_puma_jacobian_with_random_base_and_tool() -> None:
    rng = np.random.default_rng(7)
    for _ in range(50):
        arm = puma560(base=random_pose(rng), tool=random_pose(rng, 0.2))
        q = rng.uniform(arm.q_min, arm.q_max)
        np.testing.assert_allclose(arm.jacobian(q), fd_jacobian(arm, q), atol=1e-8)


def test_puma_table1_reference_pose() -> None:
    """At q = 0 (Fu-Gonzalez-Lee frames) the flange is at (a2 + a3, d2, d4 + d6)."""
    T = puma560().fk(np.zeros(6))
    np.testing.assert_allclose(T[:3, 3], [0.4318 - 0.02032, 0.14909, 0.43307 + 0.05625],
                               atol=1e-15)
    np.testing.assert_allclose(T[:3, :3], np.eye(3), atol=1e-15)


def test_base_and_tool_are_applied_and_reassignable() -> None:
    rng = np.random.default_rng(3)
    base, tool = random_pose(rng), random_pose(rng, 0.1)
    arm = puma560()
    q = rng.uniform(arm.q_min, arm.q_max)
    T0 = arm.fk(q)
    placed = puma560(base=base, tool=tool)
    np.testing.assert_allclose(placed.fk(q), base @ T0 @ tool, atol=1e-12)
    arm.base, arm.tool = base, tool  # the cached base/tool follow an assignment
    np.testing.assert_allclose(arm.fk(q), base @ T0 @ tool, atol=1e-12)
    np.testing.assert_allclose(puma560().with_base(base).fk(q), base @ T0, atol=1e-12)
    with pytest.raises(ValueError):  # in-place edits would bypass the cache
        arm.base[0, 3] = 1.0


def test_accepts_lists_and_integer_arrays() -> None:
    arm = puma560()
    q = [0, 1, 0, 1, 0, 1]
    np.testing.assert_allclose(arm.fk(q), arm.fk(np.array(q, dtype=float)), atol=0)
    np.testing.assert_allclose(arm.jacobian(np.array(q)), arm.jacobian(q), atol=0)


def test_model_velocity_limits_are_symmetric_and_appendable():
    """Pinocchio's lower velocity limit follows qd_max, so the model can be appended."""
    arm = puma560(qd_max=np.full(6, 2.0))
    np.testing.assert_array_equal(arm.model.upperVelocityLimit, np.full(6, 2.0))
    np.testing.assert_array_equal(arm.model.lowerVelocityLimit, np.full(6, -2.0))
    other = pin.Model()
    other.addJoint(0, pin.JointModelPX(), pin.SE3.Identity(), "extra")
    joined = pin.appendModel(arm.model, other, arm.tool_frame_id, pin.SE3.Identity())
    assert joined.nq == 7


@pytest.mark.parametrize("convention", ["standard", "modified"])
def test_reach_bounds_the_tool_and_is_reached_stretched_out(convention: str) -> None:
    """A planar arm of links 0.5 and 0.3 m with a 0.1 m tool reaches 0.9 m, stretched out;
    the PUMA's tool never leaves its bound, whatever the base."""
    from dualarm_qp.kinematics.reach import arm_reach

    rows = ([[0.5, 0, 0], [0.3, 0, 0]] if convention == "standard"
            else [[0, 0, 0], [0.5, 0, 0], [0.3, 0, 0]])
    planar = SerialArm(DHTable.from_rows(rows, convention), tool=trans(0.1), base=trans(1, 2))
    assert arm_reach(planar) == pytest.approx(0.9, abs=1e-15)
    stretched = planar.fk(np.zeros(planar.n))[:3, 3] - planar.base[:3, 3]
    assert np.linalg.norm(stretched) == pytest.approx(0.9, abs=1e-15)
    rng = np.random.default_rng(3)
    arm = puma560(base=random_pose(rng), tool=trans(0, 0, 0.2))
    reach = arm_reach(arm)
    far = max(np.linalg.norm(arm.fk(q)[:3, 3] - arm.base[:3, 3])
              for q in rng.uniform(-np.pi, np.pi, (500, 6)))
    assert 0.9 * reach < far <= reach
