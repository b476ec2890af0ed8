"""Grasp surfaces and sliding paths: geometry, exact derivatives, Case 1 construction."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dualarm_qp.errors import InvalidInputError, LimitsError, NonFiniteError, ShapeError
from dualarm_qp.task import (
    CenterLine,
    CurvedBar,
    CylinderSurface,
    GraspSurface,
    PlaneBar,
    case1_pose,
)

SURFACES: dict[str, GraspSurface] = {
    "plane_bar_paper": PlaneBar(),
    "plane_bar_tilted": PlaneBar(
        r_min=(-1.0, -1.0, -1.0),
        r_max=(1.0, 1.0, 1.0),
        origin=(0.1, 0.2, 0.0),
        sliding=(0.0, 1.0, 1.0),
        normal=(1.0, 1.0, -1.0),
    ),
    "cylinder": CylinderSurface(0.05, azimuth=0.7, sigma_min=-0.1, sigma_max=0.3),
    "curved_outer": CurvedBar(0.5, sigma_min=-0.2, sigma_max=0.6),
    "curved_inner": CurvedBar(0.3, side="inner", sigma_min=-0.4, sigma_max=0.5),
}
SIGMAS = (-0.15, 0.0, 0.13, 0.37, 0.45)
H = 1e-6


@pytest.fixture(params=sorted(SURFACES))
def surface(request: pytest.FixtureRequest) -> GraspSurface:
    return SURFACES[request.param]


def test_frame_is_proper_rotation_with_columns_s_n_a(surface: GraspSurface) -> None:
    for sigma in SIGMAS:
        R = surface.frame(sigma)
        np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-12)
        assert np.linalg.det(R) == pytest.approx(1.0, abs=1e-12)
        s, n, a = R[:, 0], R[:, 1], R[:, 2]
        assert abs(s @ a) < 1e-12
        np.testing.assert_allclose(n, np.cross(a, s), atol=1e-12)  # Eq. 6
        np.testing.assert_allclose(s, surface.tangent(sigma), atol=1e-12)
        np.testing.assert_allclose(a, surface.normal(sigma), atol=1e-12)


def test_point_is_on_surface_and_normal_is_grad_phi(surface: GraspSurface) -> None:
    for sigma in SIGMAS:
        r = surface.point(sigma)
        assert abs(surface.phi(r)) < 1e-12
        g = surface.grad_phi(r)
        np.testing.assert_allclose(g / np.linalg.norm(g), surface.normal(sigma), atol=1e-12)


def test_grad_phi_matches_finite_differences(surface: GraspSurface) -> None:
    r0 = surface.point(0.1) + np.array([0.01, -0.02, 0.03])
    fd = np.array(
        [(surface.phi(r0 + H * e) - surface.phi(r0 - H * e)) / (2 * H) for e in np.eye(3)]
    )
    np.testing.assert_allclose(surface.grad_phi(r0), fd, atol=1e-8)


def test_sigma_of_inverts_point(surface: GraspSurface) -> None:
    for sigma in SIGMAS:
        assert surface.sigma_of(surface.point(sigma)) == pytest.approx(sigma, abs=1e-12)


def test_sigma_of_projects_offset_points_along_normal(surface: GraspSurface) -> None:
    # A point lifted off the path along a* (and n* for the straight paths) maps back.
    for sigma in SIGMAS:
        r = surface.point(sigma) + 0.01 * surface.normal(sigma)
        assert surface.sigma_of(r) == pytest.approx(sigma, abs=1e-12)


def test_tangent_is_derivative_of_point(surface: GraspSurface) -> None:
    for sigma in SIGMAS:
        fd = (surface.point(sigma + H) - surface.point(sigma - H)) / (2 * H)
        np.testing.assert_allclose(surface.tangent(sigma), fd, atol=1e-8)
        assert np.linalg.norm(surface.tangent(sigma)) == pytest.approx(1.0, abs=1e-12)


def test_angular_rate_is_derivative_of_frame(surface: GraspSurface) -> None:
    for sigma in SIGMAS:
        R = surface.frame(sigma)
        dR = (surface.frame(sigma + H) - surface.frame(sigma - H)) / (2 * H)
        np.testing.assert_allclose(dR, pin.skew(surface.angular_rate(sigma)) @ R, atol=1e-8)
        # Same check through the log map (the convention in the trajectory tests).
        w = pin.log3(surface.frame(sigma + H) @ surface.frame(sigma - H).T) / (2 * H)
        np.testing.assert_allclose(w, surface.angular_rate(sigma), atol=1e-8)


def test_pose_is_h2_of_eq16(surface: GraspSurface) -> None:
    H2 = surface.pose(0.2)
    np.testing.assert_allclose(H2[:3, :3], surface.frame(0.2))
    np.testing.assert_allclose(H2[:3, 3], surface.point(0.2))
    np.testing.assert_array_equal(H2[3], [0, 0, 0, 1])


def test_paper_bar_matches_fig4() -> None:
    bar = PlaneBar()
    assert (bar.sigma_min, bar.sigma_max) == (0.0, 0.4)
    np.testing.assert_array_equal(bar.r_min, [0, 0, 0])
    np.testing.assert_array_equal(bar.r_max, [0, 0, 0.4])
    np.testing.assert_allclose(bar.frame(0.0), np.column_stack([[0, 0, 1], [0, -1, 0], [1, 0, 0]]))
    np.testing.assert_allclose(bar.point(0.3), [0, 0, 0.3])  # sigma = r2_z
    np.testing.assert_array_equal(bar.angular_rate(0.3), np.zeros(3))
    assert bar.sigma_center == pytest.approx(0.2)
    # Table 2 starts outside the range (r2_z = 450 mm): evaluating there must work.
    np.testing.assert_allclose(bar.point(0.45), [0, 0, 0.45])
    assert not bar.contains(0.45)
    assert bar.clamp(0.45) == 0.4


def test_paper_bar_range_from_box_with_infinite_components() -> None:
    bar = PlaneBar(r_min=(0, -math.inf, 0.1), r_max=(0, math.inf, 0.3))
    assert (bar.sigma_min, bar.sigma_max) == pytest.approx((0.1, 0.3))


def test_cylinder_at_azimuth_zero_equals_plane_bar_frame() -> None:
    cyl = CylinderSurface(0.05)
    np.testing.assert_allclose(cyl.frame(0.1), PlaneBar().frame(0.1), atol=1e-15)
    np.testing.assert_allclose(cyl.point(0.1), [0.05, 0, 0.1])


def test_curved_bar_really_turns() -> None:
    bar = CurvedBar(0.5)
    assert np.linalg.norm(bar.angular_rate(0.1)) == pytest.approx(2.0)
    s0, s1 = bar.tangent(0.0), bar.tangent(0.4)
    assert math.acos(float(s0 @ s1)) == pytest.approx(0.8)
    # At sigma = 0 the curved bar coincides with the paper's straight bar.
    np.testing.assert_allclose(bar.pose(0.0), PlaneBar().pose(0.0), atol=1e-15)
    # Bounding box contains the whole arc.
    for sig in np.linspace(bar.sigma_min, bar.sigma_max, 50):
        p = bar.point(sig)
        assert np.all(p >= bar.r_min - 1e-12) and np.all(p <= bar.r_max + 1e-12)


@settings(max_examples=60, deadline=None)
@given(
    radius=st.floats(0.05, 5.0),
    side=st.sampled_from(["outer", "inner"]),
    frac=st.floats(-0.95, 0.95),
)
def test_curved_bar_properties(radius: float, side: str, frac: float) -> None:
    sigma = frac * math.pi * radius
    bar = CurvedBar(radius, side=side, sigma_min=min(sigma, 0.0), sigma_max=max(sigma, 0.0))
    r = bar.point(sigma)
    assert abs(bar.phi(r)) < 1e-12 * max(1.0, radius)
    assert bar.sigma_of(r) == pytest.approx(sigma, abs=1e-9 * radius)
    R = bar.frame(sigma)
    np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-12)
    h = 1e-6 * radius
    fd = (bar.point(sigma + h) - bar.point(sigma - h)) / (2 * h)
    np.testing.assert_allclose(bar.tangent(sigma), fd, atol=1e-7)
    g = bar.grad_phi(r)
    np.testing.assert_allclose(g / np.linalg.norm(g), R[:, 2], atol=1e-12)


@pytest.mark.parametrize(
    ("make", "exc"),
    [
        (lambda: PlaneBar(sliding=(0, 0, 1), normal=(0, 0.1, 1)), InvalidInputError),
        (lambda: PlaneBar(sliding=(0, 0, 0)), InvalidInputError),
        (lambda: PlaneBar(r_min=(0, 0, 0.5), r_max=(0, 0, 0.4)), LimitsError),
        (lambda: PlaneBar(r_min=(0.1, 0, 0), r_max=(0.2, 0, 0.4)), LimitsError),
        (lambda: PlaneBar(r_min=(0, 0, -math.inf), r_max=(0, 0, 0.4)), LimitsError),
        (lambda: PlaneBar(r_min=(0, 0), r_max=(0, 0, 0.4)), ShapeError),
        (lambda: PlaneBar(r_min=(0, math.nan, 0)), NonFiniteError),
        (lambda: PlaneBar(sigma_min=0.3, sigma_max=0.1), LimitsError),
        (lambda: CylinderSurface(0.0), InvalidInputError),
        (lambda: CylinderSurface(0.1, sigma_min=math.nan), NonFiniteError),
        (lambda: CurvedBar(0.1, sigma_max=0.4), LimitsError),  # turns 4 rad > pi
        (lambda: CurvedBar(0.5, side="left"), InvalidInputError),
        (lambda: CurvedBar(-0.5), InvalidInputError),
    ],
)
def test_bad_construction_raises(make, exc) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(exc):
        make()


def test_bad_arguments_raise() -> None:
    bar = PlaneBar()
    with pytest.raises(NonFiniteError):
        bar.point(math.nan)
    with pytest.raises(InvalidInputError):
        bar.frame("a")  # type: ignore[arg-type]
    with pytest.raises(ShapeError):
        bar.phi([0.0, 0.0])
    with pytest.raises(NonFiniteError):
        CurvedBar(0.5).sigma_of([0.0, math.inf, 0.0])


# --- Case 1 construction (Steps 1-4, Eqs. 3-6) -------------------------------------------


def test_case1_reproduces_plane_bar() -> None:
    bar = PlaneBar()
    line = CenterLine(x=lambda z: 0.0, y=lambda z: 0.0, dx_dz=lambda z: 0.0, dy_dz=lambda z: 0.0)
    for z in (0.0, 0.2, 0.4):
        H2 = case1_pose(bar.phi, line, z, grad_phi=bar.grad_phi)
        np.testing.assert_allclose(H2, bar.pose(z), atol=1e-15)
        # Without the exact gradient: central differences of phi.
        np.testing.assert_allclose(case1_pose(bar.phi, line, z), bar.pose(z), atol=1e-9)


@pytest.mark.parametrize("side", ["outer", "inner"])
def test_case1_reproduces_curved_bar(side: str) -> None:
    rc = 0.5
    bar = CurvedBar(rc, side=side, sigma_min=-0.6, sigma_max=0.6)
    eps = 1.0 if side == "outer" else -1.0
    # Face profile x(z) = eps (sqrt(Rc^2 - z^2) - Rc), valid for |k sigma| < pi/2.
    line = CenterLine(
        x=lambda z: eps * (math.sqrt(rc * rc - z * z) - rc),
        y=lambda z: 0.0,
        dx_dz=lambda z: -eps * z / math.sqrt(rc * rc - z * z),
        dy_dz=lambda z: 0.0,
    )
    for sigma in (-0.6, -0.1, 0.0, 0.3, 0.6):
        z = float(bar.point(sigma)[2])
        H2 = case1_pose(bar.phi, line, z, grad_phi=bar.grad_phi)
        np.testing.assert_allclose(H2, bar.pose(sigma), atol=1e-12)


def test_case1_projects_non_tangent_sliding_vector() -> None:
    # Surface x = 0.1 y (a tilted plane); centre line along z with a slope in x that is
    # not tangent: s* must be projected onto the tangent plane.
    def phi(r: np.ndarray) -> float:
        return float(r[0] - 0.1 * r[1])

    line = CenterLine(x=lambda z: 0.0, y=lambda z: 0.0, dx_dz=lambda z: 0.3, dy_dz=lambda z: 0.0)
    H2 = case1_pose(phi, line, 0.1)
    R = H2[:3, :3]
    np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-9)
    a = np.array([1.0, -0.1, 0.0]) / math.sqrt(1.01)
    np.testing.assert_allclose(R[:, 2], a, atol=1e-9)
    assert abs(R[:, 0] @ a) < 1e-12
    assert R[2, 0] > 0.9  # still mostly along +z


def test_case1_errors() -> None:
    line = CenterLine(x=lambda z: 0.0, y=lambda z: 0.0, dx_dz=lambda z: 0.0, dy_dz=lambda z: 0.0)
    with pytest.raises(InvalidInputError, match="phi or grad_phi"):
        case1_pose(None, line, 0.0)
    with pytest.raises(InvalidInputError, match="vanishes"):
        case1_pose(lambda r: 0.0, line, 0.0)
    with pytest.raises(InvalidInputError, match="normal to the surface"):
        case1_pose(lambda r: float(r[2]), line, 0.0)  # surface z = 0, line along z
