"""Bad input raises the right DualArmError subclass, never a numpy broadcasting error."""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin
import pytest

from dualarm_qp.errors import (
    DualArmError,
    InvalidInputError,
    LimitsError,
    NonFiniteError,
    ShapeError,
)
from dualarm_qp.kinematics import DHTable, SerialArm, puma560
from dualarm_qp.kinematics.arm import checked_pose


@pytest.fixture
def arm() -> SerialArm:
    return puma560()


@pytest.mark.parametrize("method", ["fk", "jacobian", "fk_jacobian", "link_frames", "check_q"])
@pytest.mark.parametrize(
    ("q", "error"),
    [
        (np.zeros(5), ShapeError),
        (np.zeros(7), ShapeError),
        (np.zeros((6, 1)), ShapeError),
        (np.zeros((1, 6)), ShapeError),
        (0.0, ShapeError),
        ([0, 0, 0, 0, 0, np.nan], NonFiniteError),
        (np.array([0, 0, np.inf, 0, 0, 0]), NonFiniteError),
        (np.array([1e308, 1e308, 0, 0, 0, np.nan]), NonFiniteError),
        (["a", 0, 0, 0, 0, 0], InvalidInputError),
        (None, InvalidInputError),
    ],
)
def test_bad_joint_vector(arm: SerialArm, method: str, q: Any, error: type) -> None:
    with pytest.raises(error):
        getattr(arm, method)(q)


def test_huge_but_finite_joints_pass(arm: SerialArm) -> None:
    """The cheap finiteness test (a sum) can overflow; the full check then decides."""
    q = np.array([1e308, 1e308, 0, 0, 0, 0])
    assert np.isfinite(arm.fk(q)).all()


@pytest.mark.parametrize(
    ("build", "error"),
    [
        (lambda: DHTable.from_rows(np.zeros((3, 5))), ShapeError),
        (lambda: DHTable.from_rows(np.zeros(4)), ShapeError),
        (lambda: DHTable.from_rows(np.zeros((0, 4))), InvalidInputError),
        (lambda: DHTable.from_rows([[0, 0, "x"]]), InvalidInputError),
        (lambda: DHTable.from_rows([[0, np.nan, 0]]), NonFiniteError),
        (lambda: DHTable(np.zeros(3), np.zeros(2), np.zeros(3), np.zeros(3)), ShapeError),
        (lambda: DHTable(np.zeros((3, 1)), np.zeros(3), np.zeros(3), np.zeros(3)), ShapeError),
        (lambda: DHTable.from_rows(np.zeros((2, 3)), "craig"), InvalidInputError),  # type: ignore[arg-type]
    ],
)
def test_bad_dh_table(build: Any, error: type) -> None:
    with pytest.raises(error):
        build()


def _dh(n: int = 3) -> DHTable:
    return DHTable.from_rows(np.ones((n, 3)))


@pytest.mark.parametrize(
    ("kwargs", "error"),
    [
        ({"q_min": [0, 0, 1], "q_max": [1, 1, 0]}, LimitsError),
        ({"q_min": [0, 0], "q_max": [1, 1, 1]}, ShapeError),
        ({"q_min": [0, 0, np.nan]}, NonFiniteError),
        ({"qd_max": [1, 0, 1]}, LimitsError),
        ({"qd_max": -1.0}, LimitsError),
        ({"base": 2 * np.eye(4)}, InvalidInputError),
        ({"base": np.diag([1.0, 1.0, -1.0, 1.0])}, InvalidInputError),  # reflection
        ({"base": np.eye(3)}, ShapeError),
        ({"tool": np.full((4, 4), np.nan)}, NonFiniteError),
        ({"tool": np.vstack([np.eye(4)[:3], [0, 0, 1, 1]])}, InvalidInputError),
    ],
)
def test_bad_arm_parameters(kwargs: dict, error: type) -> None:
    with pytest.raises(error):
        SerialArm(_dh(), **kwargs)


def test_dh_must_be_a_table() -> None:
    with pytest.raises(InvalidInputError):
        SerialArm(np.ones((3, 3)))  # type: ignore[arg-type]


def test_reassigning_a_bad_base_is_rejected(arm: SerialArm) -> None:
    with pytest.raises(InvalidInputError):
        arm.base = np.diag([2.0, 1.0, 1.0, 1.0])


def test_all_errors_share_the_root() -> None:
    for error in (ShapeError, NonFiniteError, LimitsError, InvalidInputError):
        assert issubclass(error, DualArmError) and issubclass(error, ValueError)


def test_checked_pose_fast_path_agrees_with_as_pose() -> None:
    good = np.eye(4)
    good[:3, :3] = pin.rpy.rpyToMatrix(0.3, 0.0, 0.0)
    assert checked_pose(good, "T") is good
    for bad in (np.diag([1.0, 1.0, -1.0, 1.0]), 1.01 * np.eye(4), np.zeros((4, 4))):
        with pytest.raises(InvalidInputError):
            checked_pose(bad, "T")
    with pytest.raises(ShapeError):
        checked_pose(np.eye(3), "T")
    with pytest.raises(NonFiniteError):
        checked_pose(np.full((4, 4), np.inf), "T")


def test_dh_table_arrays_are_read_only_copies() -> None:
    a = np.ones(3)
    dh = DHTable(a, np.zeros(3), np.zeros(3), np.zeros(3))
    a[0] = 5.0
    assert dh.a[0] == 1.0
    with pytest.raises(ValueError):
        dh.a[0] = 2.0
