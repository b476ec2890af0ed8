"""Case 2 support without grasping (Eqs. 7-13), including the paper's worked example.

The printed Eq. 11 has the wrong sign on the gravity terms relative to Eqs. 7-9:
``test_printed_eq11_violates_equilibrium`` proves it, ``test_worked_example_eq11_corrected``
checks the corrected formula (see docs/paper_corrections.md).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dualarm_qp.errors import InvalidInputError, LimitsError
from dualarm_qp.task import (
    CurvedBar,
    CylinderSurface,
    PlaneBar,
    equilibrium_residual,
    solve_support,
    support_line,
    support_point,
    support_sliding_vector,
)

M = 3.0  # kg
G = 9.81  # m/s^2
R1Y, ZMAX = 0.05, 0.425  # m: leader hand at the end of the 850 mm bar
R1 = np.array([0.0, R1Y, -ZMAX])
GRAV_UP_X = np.array([-G, 0.0, 0.0])  # x_o aligned with z_B (up): g_x = -9.81


def eq11_corrected(g_x: float, h: float) -> np.ndarray:
    k = g_x * M / h
    return np.array([0.0, R1Y * (1.0 + k), -ZMAX * (1.0 + k)])


def eq11_printed(g_x: float, h: float) -> np.ndarray:
    return np.array([0.0, -g_x * R1Y * M / h + R1Y, g_x * ZMAX * M / h - ZMAX])


def residual_for(r2: np.ndarray, h: float, g_x: float) -> np.ndarray:
    ff = h * np.array([1.0, 0.0, 0.0])
    fl = -ff - M * np.array([g_x, 0.0, 0.0])  # Eq. 8
    return equilibrium_residual(R1, r2, fl, ff, mass=M, gravity=[g_x, 0.0, 0.0])


@pytest.mark.parametrize("g_x", [-G, G, -1.6])
@pytest.mark.parametrize("h", [5.0, 20.0, 29.43, 100.0])
def test_worked_example_eq11_corrected(g_x: float, h: float) -> None:
    sol = support_point(R1, mass=M, gravity=[g_x, 0.3, -0.2], h=h)  # g_y, g_z unused
    np.testing.assert_allclose(sol.r2, eq11_corrected(g_x, h), atol=1e-14)
    assert sol.residual < 1e-12
    np.testing.assert_allclose(residual_for(sol.r2, h, g_x), 0.0, atol=1e-12)
    np.testing.assert_allclose(sol.f_follower, [h, 0, 0])
    # Eq. 12 on the corrected locus.
    assert sol.r2[1] == pytest.approx(-(R1Y / ZMAX) * sol.r2[2], abs=1e-15)


@pytest.mark.parametrize("g_x", [-G, G])
def test_printed_eq11_violates_equilibrium(g_x: float) -> None:
    h = 20.0
    printed = eq11_printed(g_x, h)
    # Not an equilibrium of Eqs. 7-8 (moment residual of order M g_x zmax) ...
    assert np.max(np.abs(residual_for(printed, h, g_x))) > 1.0
    # ... but exactly the equilibrium for the opposite gravity sign (g~ -> -g~).
    np.testing.assert_allclose(printed, eq11_corrected(-g_x, h), atol=1e-15)
    # Eq. 12 holds for the printed formula too: the locus line is the same.
    assert printed[1] == pytest.approx(-(R1Y / ZMAX) * printed[2], abs=1e-15)


def test_corrected_sign_is_the_physical_one() -> None:
    # x_o up: a follower pushing up with between half and all of the weight must sit
    # on the far half of the bar (0 < z <= zmax), not beyond the leader's end.
    for h in (0.55 * M * G, 0.8 * M * G, 0.99 * M * G):
        z = support_point(R1, mass=M, gravity=GRAV_UP_X, h=h).r2[2]
        assert 0.0 < z <= ZMAX
        assert eq11_printed(-G, h)[2] < -ZMAX  # printed: outside the bar
    # Carrying the whole weight puts the follower under the mass centre.
    np.testing.assert_allclose(
        support_point(R1, mass=M, gravity=GRAV_UP_X, h=M * G).r2, 0.0, atol=1e-15
    )


def test_eq13_sliding_vector_and_support_line() -> None:
    line = support_line(R1, mass=M, gravity=GRAV_UP_X, r_min=(0, -0.1, -ZMAX), r_max=(0, 0.1, ZMAX))
    s13 = np.array([0.0, -R1Y / ZMAX, 1.0]) / math.sqrt(1.0 + (R1Y / ZMAX) ** 2)
    np.testing.assert_allclose(line.tangent(0.0), s13, atol=1e-15)
    np.testing.assert_allclose(line.normal(0.0), [1, 0, 0])
    np.testing.assert_allclose(line.origin, 0.0, atol=1e-15)  # passes the mass centre
    # The whole line satisfies Eq. 12 and carries the closed-form forces.
    for h in (16.0, 20.0, 29.43, 60.0):
        sigma = line.sigma_at(h)
        r = line.point(sigma)
        np.testing.assert_allclose(r, eq11_corrected(-G, h), atol=1e-14)
        assert line.force(sigma) == pytest.approx(h, rel=1e-12)
        assert line.sigma_of(r) == pytest.approx(sigma, abs=1e-14)
        sol = line.solution(sigma)
        assert sol.h == pytest.approx(h) and sol.residual < 1e-12
    # Range: from the leader (h -> inf) to the bar end at z = zmax.
    assert line.sigma_min == pytest.approx(-math.hypot(R1Y, ZMAX))
    assert line.point(line.sigma_max)[2] == pytest.approx(ZMAX)
    # With a force cap the range starts where h = h_max.
    capped = support_line(
        R1, mass=M, gravity=GRAV_UP_X, r_min=(0, -0.1, -ZMAX), r_max=(0, 0.1, ZMAX), h_max=60.0
    )
    assert capped.force(capped.sigma_min) == pytest.approx(60.0)


def test_support_line_errors() -> None:
    box = {"r_min": (0, -0.1, -ZMAX), "r_max": (0, 0.1, ZMAX)}
    with pytest.raises(InvalidInputError, match="degenerate"):
        support_line(R1, mass=M, gravity=[0.0, -G, 0.0], **box)
    with pytest.raises(LimitsError):
        support_line(R1, mass=M, gravity=GRAV_UP_X)  # unbounded line
    line = support_line(R1, mass=M, gravity=GRAV_UP_X, **box)
    with pytest.raises(InvalidInputError, match="no pushing support"):
        line.solution(line.sigma_inf - 0.1)
    with pytest.raises(InvalidInputError):
        line.sigma_at(-1.0)
    with pytest.raises(InvalidInputError, match="mass"):
        support_point(R1, mass=0.0, gravity=GRAV_UP_X, h=1.0)
    with pytest.raises(InvalidInputError, match="push"):
        support_point(R1, mass=M, gravity=GRAV_UP_X, h=0.0)
    # Plane y = 0 with gravity along x and the leader off the x axis: no normal-only push
    # can balance the moment (Eq. 9 solvability).
    with pytest.raises(InvalidInputError, match="normal"):
        support_point([0.1, 0.0, -0.4], mass=M, gravity=GRAV_UP_X, h=10.0, normal=(0, 1, 0))


@settings(max_examples=80, deadline=None)
@given(
    r1=st.tuples(*[st.floats(-1.0, 1.0)] * 3),
    g_x=st.floats(-20.0, 20.0).filter(lambda v: abs(v) > 1e-3),
    h=st.floats(0.1, 500.0),
    offset=st.floats(-0.5, 0.5),
)
def test_plane_support_is_an_equilibrium(
    r1: tuple[float, float, float], g_x: float, h: float, offset: float
) -> None:
    sol = support_point(r1, mass=M, gravity=[g_x, 0, 0], h=h, offset=offset)
    assert sol.r2[0] == pytest.approx(offset, abs=1e-12)  # on the plane x = offset
    res = equilibrium_residual(
        r1, sol.r2, sol.f_leader, sol.f_follower, mass=M, gravity=[g_x, 0, 0]
    )
    scale = M * abs(g_x) * (1.0 + np.linalg.norm(r1)) + h * (1.0 + np.linalg.norm(sol.r2))
    assert np.max(np.abs(res)) <= 1e-12 * scale


def test_general_solver_matches_plane_closed_form() -> None:
    bar = PlaneBar(r_min=(0, -1, -1), r_max=(0, 1, 1))
    for h in (10.0, 25.0):
        sol = solve_support(bar, R1, mass=M, gravity=GRAV_UP_X, h=h, r2_guess=[0.0, 0.0, 0.0])
        np.testing.assert_allclose(sol.r2, eq11_corrected(-G, h), atol=1e-9)
    s = support_sliding_vector(bar, R1, mass=M, gravity=GRAV_UP_X, h=20.0, r2_guess=[0, 0, 0])
    line = support_line(R1, mass=M, gravity=GRAV_UP_X, r_min=(0, -1, -1), r_max=(0, 1, 1))
    np.testing.assert_allclose(s, line.tangent(0.0), atol=1e-6)


def test_general_solver_on_curved_surfaces() -> None:
    # Cylinder along z: leader in the x-z plane, the support stays on the generator y = 0.
    cyl = CylinderSurface(0.05, sigma_min=-0.4, sigma_max=0.4)
    r1 = np.array([0.07, 0.0, -0.3])
    sol = solve_support(cyl, r1, mass=M, gravity=GRAV_UP_X, h=20.0, r2_guess=[0.05, 0.01, 0.1])
    assert abs(cyl.phi(sol.r2)) < 1e-9 and sol.residual < 1e-8
    np.testing.assert_allclose(sol.r2, [0.05, 0.0, -0.3 * (1.0 - M * G / 20.0)], atol=1e-8)
    # Curved bar bent in x-z: the support locus is the arc itself; s* is its tangent.
    bar = CurvedBar(0.8, sigma_min=-0.5, sigma_max=0.5)
    r1 = bar.point(-0.45) + np.array([0.0, 0.0, 0.0])
    guess = bar.point(0.1)
    sol = solve_support(bar, r1, mass=M, gravity=GRAV_UP_X, h=25.0, r2_guess=guess)
    assert abs(bar.phi(sol.r2)) < 1e-9 and sol.residual < 1e-8 and sol.h > 0
    sigma = bar.sigma_of(sol.r2)
    np.testing.assert_allclose(sol.normal, bar.normal(sigma), atol=1e-8)
    s = support_sliding_vector(bar, r1, mass=M, gravity=GRAV_UP_X, h=25.0, r2_guess=sol.r2)
    assert abs(abs(s @ bar.tangent(sigma)) - 1.0) < 1e-6


def test_general_solver_reports_no_equilibrium() -> None:
    # Plane y = 0, gravity along x, leader off the plane's normal axis: no solution.
    plane = PlaneBar(r_min=(-1, 0, -1), r_max=(1, 0, 1), sliding=(0, 0, 1), normal=(0, 1, 0))
    with pytest.raises(InvalidInputError, match="no support equilibrium"):
        solve_support(
            plane, [0.1, 0.0, -0.4], mass=M, gravity=GRAV_UP_X, h=10.0, r2_guess=[0, 0, 0]
        )
