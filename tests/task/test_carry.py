"""The carried-object model: grasps as joints, poses and Jacobians (Eqs. 14-16, 25-27)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dualarm_qp import puma560
from dualarm_qp.task.carry import CarryModel
from dualarm_qp.task.surfaces import CurvedBar, CylinderSurface, PlaneBar

SURFACES = {
    "plane_bar": lambda: PlaneBar(origin=(0.01, 0.02, -0.05), sliding=(0.6, 0.0, 0.8),
                                  normal=(0.8, 0.0, -0.6), r_min=(-1, -1, -1), r_max=(1, 1, 1),
                                  sigma_min=-0.2, sigma_max=0.4),
    "cylinder": lambda: CylinderSurface(0.05, azimuth=0.7, sigma_min=-0.2, sigma_max=0.3),
    "curved_outer": lambda: CurvedBar(0.5, sigma_min=-0.2, sigma_max=0.3),
    "curved_inner": lambda: CurvedBar(0.8, side="inner", sigma_min=-0.3, sigma_max=0.3),
}


@pytest.mark.parametrize("name", sorted(SURFACES))
@given(sigma=st.floats(-0.3, 0.5))
@settings(max_examples=25, deadline=None)
def test_slide_joint_reproduces_the_grasp_frame(name, sigma):
    surface = SURFACES[name]()
    j = surface.slide_joint()
    theta = j.rate * sigma
    M = np.eye(4)
    if j.kind == "prismatic":
        M[:3, 3] = theta * (np.eye(3)[0] if j.axis == "x" else np.eye(3)[1])
    else:
        M[:3, :3] = pin.exp3(theta * (np.eye(3)[0] if j.axis == "x" else np.eye(3)[1]))
    np.testing.assert_allclose(j.placement @ M @ j.child, surface.pose(sigma), atol=1e-14)


def _fd(model: CarryModel, q_l, s_f, s_l, which: str):
    """Central differences of a frame's pose over [q_l, s_f, s_l] (world [v; w] rows)."""
    x = np.r_[q_l, s_f, s_l]
    n = x.size if model.n_grasp == 2 else x.size - 1
    J = np.zeros((6, n))
    h = 1e-6
    for i in range(n):
        e = np.zeros(x.size)
        e[i] = h
        Tp = getattr(model.update(x[:6] + e[:6], x[6] + e[6], x[7] + e[7]), which).copy()
        Tm = getattr(model.update(x[:6] - e[:6], x[6] - e[6], x[7] - e[7]), which).copy()
        J[:3, i] = (Tp[:3, 3] - Tm[:3, 3]) / (2 * h)
        J[3:, i] = pin.log3(Tp[:3, :3] @ Tm[:3, :3].T) / (2 * h)
    return J


@pytest.mark.parametrize("leader", [None, "plane_bar", "curved_inner"])
@pytest.mark.parametrize("name", sorted(SURFACES))
def test_poses_and_jacobians(name, leader):
    rng = np.random.default_rng(abs(hash((name, leader))) % 2**32)
    arm = puma560(base=pin.SE3(pin.exp3(rng.normal(size=3) * 0.3),
                               rng.normal(size=3) * 0.2).homogeneous)
    surface = SURFACES[name]()
    lead = None if leader is None else SURFACES[leader]()
    H1 = pin.SE3(pin.exp3(rng.normal(size=3)), rng.normal(size=3) * 0.1).homogeneous
    model = CarryModel(arm, surface, H1, lead)
    assert model.n_grasp == (1 if lead is None else 2)
    for _ in range(3):
        q = rng.uniform(-2.0, 2.0, 6)
        s_f, s_l = rng.uniform(-0.2, 0.3), rng.uniform(-0.2, 0.3)
        kin = model.update(q, s_f, s_l)
        T_l, J_l = arm.fk_jacobian(q)
        H = H1 if lead is None else np.linalg.inv(lead.pose(s_l))
        np.testing.assert_allclose(kin.T_tool, T_l, atol=1e-14)
        np.testing.assert_allclose(kin.J_tool, J_l, atol=1e-14)
        np.testing.assert_allclose(kin.T_object, T_l @ H, atol=1e-13)
        np.testing.assert_allclose(kin.T_target, T_l @ H @ surface.pose(s_f), atol=1e-13)
        for which, J in (("T_object", kin.J_object), ("T_target", kin.J_target)):
            np.testing.assert_allclose(J, _fd(model, q, s_f, s_l, which), atol=1e-7,
                                       err_msg=which)
        # The object does not move with the follower's grasp.
        assert not kin.J_object[:, 6].any()
