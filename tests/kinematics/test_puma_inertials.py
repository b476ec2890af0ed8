"""The PUMA 560's link inertias: Armstrong, Khatib and Burdick (1986) in Table 1's frames.

The oracle here is written in the source's own convention: the modified DH link frames
of that paper, with its masses, centres and inertias typed in again from the paper's
table (not read from the library), and rigid-body statics and dynamics from the textbook
formulas (plain numpy, ``dh_oracle`` for the link transforms). Its twists and link
lengths are Table 1's; its offsets place the same joint axes as Table 1 does (the two
sources' ``d`` differ by at most 1 mm; the library keeps Table 1's kinematics). The
library's converted model must give the same gravity torques and the same joint-space
inertia matrix at random joints.
"""

from __future__ import annotations

import dh_oracle
import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dualarm_qp.kinematics.puma560 import puma560

G = 9.81

#: The source's modified DH rows ``(a_{i-1}, alpha_{i-1}, d_i)``: its own twists and
#: lengths; d2 its own (the link-2 frame 243.5 mm up the shoulder axis), d3 such that
#: d2 + d3 is Table 1's d2 (149.09 mm; the source says 150.1), d4 Table 1's (433.07;
#: the source says 433.1).
MDH = np.array([[0.0, 0.0, 0.0],
                [0.0, -np.pi / 2, 0.2435],
                [0.4318, 0.0, 0.14909 - 0.2435],
                [-0.02032, np.pi / 2, 0.43307],
                [0.0, -np.pi / 2, 0.0],
                [0.0, np.pi / 2, 0.0]])
#: Table 1 (standard DH rows ``(a, alpha, d, offset)``), typed in again.
TABLE1 = np.column_stack([[0.0, 0.4318, -0.02032, 0.0, 0.0, 0.0],
                          np.deg2rad([-90.0, 0.0, 90.0, -90.0, 90.0, 0.0]),
                          [0.0, 0.14909, 0.0, 0.43307, 0.0, 0.05625], np.zeros(6)])
#: The source's table: mass [kg], centre [m] and principal inertia about the centre
#: [kg m^2] in its link frames.
SOURCE = [
    (0.0, (0.0, 0.0, 0.0), (0.0, 0.0, 0.35)),
    (17.4, (0.068, 0.006, -0.016), (0.13, 0.524, 0.539)),
    (4.8, (0.0, -0.070, 0.014), (0.066, 0.0125, 0.066)),
    (0.82, (0.0, 0.0, -0.019), (1.8e-3, 1.8e-3, 1.3e-3)),
    (0.34, (0.0, 0.0, 0.0), (0.3e-3, 0.3e-3, 0.4e-3)),
    (0.09, (0.0, 0.0, 0.032), (0.15e-3, 0.15e-3, 0.04e-3)),
]


def _frames(q: np.ndarray) -> list[np.ndarray]:
    """The source's link frames 1..6 in the base frame."""
    T = np.eye(4)
    out = []
    for row, qi in zip(MDH, q, strict=True):
        T = T @ dh_oracle.link(np.r_[row, 0.0], float(qi), "modified")
        out.append(T)
    return out


def _source_statics(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Gravity torques (what holds the arm still) and the inertia matrix, source's way."""
    frames = _frames(q)
    axes = [T[:3, 2] for T in frames]
    origins = [T[:3, 3] for T in frames]
    tau = np.zeros(6)
    M = np.zeros((6, 6))
    for i, (m, c, inertia) in enumerate(SOURCE):
        R = frames[i][:3, :3]
        centre = frames[i][:3, 3] + R @ np.asarray(c)
        Jv = np.zeros((3, 6))
        Jw = np.zeros((3, 6))
        for j in range(i + 1):
            Jv[:, j] = np.cross(axes[j], centre - origins[j])
            Jw[:, j] = axes[j]
        # V = m g z_c: its gradient is the torque that holds the link up.
        tau += m * G * Jv[2]
        I_world = R @ np.diag(inertia) @ R.T
        M += m * Jv.T @ Jv + Jw.T @ I_world @ Jw
    return tau, M


def test_the_source_frames_place_table_1s_joints() -> None:
    """The oracle's wrist centre is Table 1's (so its link frames sit on the same arm)."""
    rng = np.random.default_rng(3)
    for _ in range(20):
        q = rng.uniform(-np.pi, np.pi, 6)
        T = np.eye(4)
        for row, qi in zip(TABLE1[:4], q[:4], strict=True):  # frame 4: the wrist centre
            T = T @ dh_oracle.link(row, float(qi), "standard")
        np.testing.assert_allclose(_frames(q)[5][:3, 3], T[:3, 3], atol=1e-12)
        for i in (3, 4, 5):  # the wrist axes: z of the source's frames 4..6
            Ti = np.eye(4)
            for row, qi in zip(TABLE1[:i], q[:i], strict=True):
                Ti = Ti @ dh_oracle.link(row, float(qi), "standard")
            np.testing.assert_allclose(_frames(q)[i][:3, 2], Ti[:3, 2], atol=1e-12)


@settings(max_examples=40, deadline=None)
@given(st.lists(st.floats(-np.pi, np.pi), min_size=6, max_size=6))
def test_converted_model_matches_the_source(q_list: list[float]) -> None:
    q = np.array(q_list)
    arm = puma560()
    model, data = arm.model, arm.data
    tau_src, M_src = _source_statics(q)
    np.testing.assert_allclose(pin.computeGeneralizedGravity(model, data, q), tau_src,
                               atol=1e-10)
    M = pin.crba(model, data, q)
    M = np.triu(M) + np.triu(M, 1).T
    np.testing.assert_allclose(M, M_src, atol=1e-10)


def test_gravity_is_not_trivially_zero() -> None:
    """The comparison above is not vacuous: the shoulder holds tens of N m stretched out."""
    tau, _ = _source_statics(np.zeros(6))
    assert abs(tau[1]) > 30.0
    arm = puma560()
    assert sum(arm.model.inertias[j].mass for j in range(1, 7)) == pytest.approx(23.45)
