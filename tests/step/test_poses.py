"""``dq.pose``: the experiment files' pose convention, checked against independent oracles.

The oracles are explicit elementary rotations ``Rz(yaw) Ry(pitch) Rx(roll)`` and SciPy's
``Rotation.from_euler("ZYX", [yaw, pitch, roll])`` (intrinsic z, y', x''). A pose read
from an experiment file must be the matrix ``dq.pose`` gives for the same numbers.
"""

from __future__ import annotations

import copy
import math
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st
from pydantic import ValidationError
from scipy.spatial.transform import Rotation

import dualarm_qp as dq
from dualarm_qp.errors import DualArmError, InvalidInputError, NonFiniteError, ShapeError
from dualarm_qp.experiments.config import ANGLE_SCALE, LENGTH_SCALE, PoseSpec, parse_config
from dualarm_qp.poses import ANGLE_UNITS, LENGTH_UNITS

ROOT = Path(__file__).resolve().parents[2]
MM_DEG = {"length": "mm", "angle": "deg"}

angles = st.floats(-2 * math.pi, 2 * math.pi, allow_nan=False)
coords = st.floats(-5.0, 5.0, allow_nan=False)
vec3 = st.tuples(coords, coords, coords)
rpy3 = st.tuples(angles, angles, angles)


def rot_x(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_y(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rot_z(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


@settings(max_examples=200, deadline=None)
@given(position=vec3, rpy=rpy3)
def test_rpy_is_rz_ry_rx_about_fixed_axes(position, rpy):
    roll, pitch, yaw = rpy
    T = dq.pose(position, rpy=rpy)
    explicit = rot_z(yaw) @ rot_y(pitch) @ rot_x(roll)
    np.testing.assert_allclose(T[:3, :3], explicit, rtol=0, atol=1e-14)
    scipy_zyx = Rotation.from_euler("ZYX", [yaw, pitch, roll]).as_matrix()
    np.testing.assert_allclose(T[:3, :3], scipy_zyx, rtol=0, atol=1e-14)
    np.testing.assert_array_equal(T[:3, 3], position)
    np.testing.assert_array_equal(T[3], [0.0, 0.0, 0.0, 1.0])


def test_each_angle_turns_about_its_own_axis():
    quarter = math.pi / 2
    # roll about x: y goes to z; pitch about y: z goes to x; yaw about z: x goes to y.
    np.testing.assert_allclose(dq.pose(rpy=[quarter, 0, 0])[:3, 1], [0, 0, 1], atol=1e-15)
    np.testing.assert_allclose(dq.pose(rpy=[0, quarter, 0])[:3, 2], [1, 0, 0], atol=1e-15)
    np.testing.assert_allclose(dq.pose(rpy=[0, 0, quarter])[:3, 0], [0, 1, 0], atol=1e-15)
    np.testing.assert_array_equal(dq.pose(), np.eye(4))


@settings(max_examples=100, deadline=None)
@given(position=vec3, rpy=rpy3)
def test_millimetres_and_degrees_are_scaled_to_si(position, rpy):
    T_file = dq.pose(np.array(position) * 1e3, rpy=np.degrees(rpy), units=MM_DEG)
    T_si = dq.pose(position, rpy=rpy)
    np.testing.assert_allclose(T_file, T_si, rtol=1e-14, atol=1e-13)
    # Each key alone; a missing key is SI.
    np.testing.assert_allclose(dq.pose(np.array(position) * 1e3, rpy=rpy,
                                       units={"length": "mm"}), T_si, rtol=1e-14, atol=1e-13)
    np.testing.assert_allclose(dq.pose(position, rpy=np.degrees(rpy), units={"angle": "deg"}),
                               T_si, rtol=1e-14, atol=1e-13)
    np.testing.assert_array_equal(dq.pose(position, rpy=rpy, units={"length": "m",
                                                                    "angle": "rad"}), T_si)


@settings(max_examples=100, deadline=None)
@given(position=vec3, seed=st.integers(0, 2**32 - 1))
def test_a_rotation_matrix_is_kept_and_its_units_do_not_apply(position, seed):
    R = Rotation.random(random_state=seed).as_matrix()
    T = dq.pose(np.array(position) * 1e3, rotation=R, units=MM_DEG)
    np.testing.assert_allclose(T[:3, :3], R, rtol=0, atol=1e-14)
    np.testing.assert_allclose(T[:3, 3], position, rtol=1e-14, atol=1e-14)
    # The rpy form and the matrix form of one orientation give one pose.
    rpy = Rotation.from_matrix(R).as_euler("ZYX")[::-1]
    np.testing.assert_allclose(dq.pose(position, rpy=rpy), dq.pose(position, rotation=R),
                               rtol=0, atol=1e-13)


@settings(max_examples=100, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_a_rounded_rotation_is_accepted_and_made_orthonormal(seed):
    R = Rotation.random(random_state=seed).as_matrix()
    rounded = R.round(7)  # at most 5e-8 per entry: R^T R within 1e-6 of the identity
    Rp = dq.pose(rotation=rounded)[:3, :3]
    np.testing.assert_allclose(Rp.T @ Rp, np.eye(3), rtol=0, atol=1e-14)
    assert np.linalg.det(Rp) == pytest.approx(1.0, abs=1e-14)
    np.testing.assert_allclose(Rp, R, rtol=0, atol=1e-6)


@settings(max_examples=200, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), exponent=st.floats(-8.0, -5.0))
def test_the_file_and_python_accept_the_same_rotations(seed, exponent):
    """Near the tolerance (1e-6) both readings take the same decision."""
    rng = np.random.default_rng(seed)
    R = Rotation.random(random_state=seed).as_matrix() + rng.normal(size=(3, 3)) * 10**exponent
    try:
        PoseSpec(rotation=R.tolist())
        file_accepts = True
    except ValidationError:
        file_accepts = False
    try:
        dq.pose(rotation=R)
        python_accepts = True
    except InvalidInputError:
        python_accepts = False
    assert file_accepts == python_accepts


def test_the_unit_tables_are_those_of_the_files():
    assert LENGTH_UNITS == LENGTH_SCALE
    assert ANGLE_UNITS == ANGLE_SCALE


def test_a_pose_from_a_file_is_the_pose_from_python():
    """Tool, H1 and path start of an experiment file in mm and deg, against dq.pose."""
    data = yaml.safe_load((ROOT / "configs" / "puma_beam_limits.yaml").read_text())
    cfg = copy.deepcopy(data)
    assert cfg["units"] == {"length": "mm", "angle": "deg", "time": "s"}
    tool = {"position": [10.0, -20.0, 55.0], "rpy": [3.0, -7.0, 12.5]}
    H1 = {"position": [0.0, 5.0, -15.0], "rpy": [-4.0, 2.0, 6.0]}
    start = cfg["trajectory"]["start"]  # given as a rotation matrix
    cfg["leader"]["tool"] = tool
    cfg["object"]["H1"] = H1
    exp = dq.build_experiment(parse_config(cfg))
    np.testing.assert_array_equal(exp.task.leader.tool, dq.pose(**tool, units=MM_DEG))
    np.testing.assert_array_equal(exp.task.H1, dq.pose(**H1, units=MM_DEG))
    np.testing.assert_allclose(exp.task.trajectory.pose(0.0), dq.pose(**start, units=MM_DEG),
                               rtol=0, atol=1e-15)


@pytest.mark.parametrize(("kwargs", "error", "message"), [
    ({"position": [1, 2]}, ShapeError, r"position must have shape \(3,\), got \(2,\)"),
    ({"position": [[1, 2, 3]]}, ShapeError, "position must have shape"),
    ({"rpy": [0, 0, 0, 0]}, ShapeError, r"rpy must have shape \(3,\)"),
    ({"rotation": np.eye(4)}, ShapeError, r"rotation must have shape \(3, 3\)"),
    ({"position": [0, math.nan, 0]}, NonFiniteError, "position contains NaN"),
    ({"rpy": [0, math.inf, 0]}, NonFiniteError, "rpy contains NaN or infinite"),
    ({"position": ["a", 0, 0]}, InvalidInputError, "position must be an array of numbers"),
    ({"rpy": [0, 0, 0], "rotation": np.eye(3)}, InvalidInputError,
     "either rpy or rotation, not both"),
    ({"rotation": 2 * np.eye(3)}, InvalidInputError, "must be a rotation matrix: R.T R is 3"),
    ({"rotation": np.diag([1.0, 1.0, -1.0])}, InvalidInputError, "reflection"),
    ({"rotation": np.zeros((3, 3))}, InvalidInputError, "must be a rotation matrix"),
    ({"units": {"length": "cm"}}, InvalidInputError,
     "unknown length unit 'cm' \\(valid: m, mm\\)"),
    ({"units": {"angle": "grad"}}, InvalidInputError,
     "unknown angle unit 'grad' \\(valid: rad, deg\\)"),
    ({"units": {"length": "mm", "time": "s"}}, InvalidInputError,
     "unknown key 'time' \\(valid: length, angle\\)"),
    ({"units": "mm"}, InvalidInputError, "units must be a mapping"),
    ({"units": {"length": 1e-3}}, InvalidInputError, "unknown length unit 0.001"),
])
def test_bad_input_is_a_clear_error(kwargs, error, message):
    with pytest.raises(error, match=message) as info:
        dq.pose(**kwargs)
    assert isinstance(info.value, DualArmError)
    assert isinstance(info.value, ValueError)


def test_the_result_is_a_new_array():
    R = np.eye(3)
    p = np.array([1.0, 2.0, 3.0])
    T = dq.pose(p, rotation=R)
    T[:3, :] = 0.0
    np.testing.assert_array_equal(p, [1.0, 2.0, 3.0])
    np.testing.assert_array_equal(R, np.eye(3))
