"""Case 2 support without grasping (Eqs. 7-13), including the paper's worked example.

The printed Eq. 11 has the wrong sign on the gravity terms relative to Eqs. 7-9:
``test_printed_eq11_violates_equilibrium`` proves it, ``test_worked_example_eq11_corrected``
checks the corrected formula (see docs/paper_corrections.md).
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dualarm_qp import puma560
from dualarm_qp.errors import InvalidInputError, LimitsError
from dualarm_qp.experiments.config import load_config
from dualarm_qp.experiments.setup import Experiment, build_experiment
from dualarm_qp.step.build import StepBuilder
from dualarm_qp.step.options import StepOptions
from dualarm_qp.step.state import DualArmState
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
from dualarm_qp.task.carry import CarryModel
from dualarm_qp.task.contact import SupportContact

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


# --- The mass centre, the support contact and its line per orientation ------------------

BEAM_BOX: dict[str, Any] = {"r_min": (0.0, -0.2, -0.1), "r_max": (0.0, 0.2, 0.5)}


@pytest.mark.parametrize("h", [10.0, 29.43, 80.0])
def test_mass_centre_is_a_shift_of_coordinates(h: float) -> None:
    # Writing everything about the mass centre r_c (r -> r - r_c, the plane offset with
    # it) must give the same contact point, shifted back.
    rc = np.array([0.0, 0.03, 0.2])
    sol = support_point(R1, mass=M, gravity=GRAV_UP_X, h=h, mass_centre=rc)
    shifted = support_point(R1 - rc, mass=M, gravity=GRAV_UP_X, h=h, offset=-rc[0])
    np.testing.assert_allclose(sol.r2, shifted.r2 + rc, atol=1e-15)
    assert sol.residual < 1e-12
    res = equilibrium_residual(R1, sol.r2, sol.f_leader, sol.f_follower, mass=M,
                               gravity=GRAV_UP_X, mass_centre=rc)
    np.testing.assert_allclose(res, 0.0, atol=1e-12)
    # The same forces without the weight's moment about the origin do not balance.
    assert np.max(np.abs(equilibrium_residual(R1, sol.r2, sol.f_leader, sol.f_follower,
                                              mass=M, gravity=GRAV_UP_X))) > 1.0
    # Pushing with the whole weight puts the follower under the mass centre.
    under = support_point(R1, mass=M, gravity=GRAV_UP_X, h=M * G, mass_centre=rc)
    np.testing.assert_allclose(under.r2, rc, atol=1e-15)


def test_support_line_through_leader_and_mass_centre() -> None:
    rc = np.array([0.0, 0.04, 0.1])
    line = support_line(R1, mass=M, gravity=GRAV_UP_X, mass_centre=rc, **BEAM_BOX)
    d = rc - R1
    np.testing.assert_allclose(line.tangent(0.0), d / np.linalg.norm(d), atol=1e-15)
    for h in (20.0, M * G, 60.0):
        sigma = line.sigma_at(h)
        sol = line.solution(sigma)
        assert sol.h == pytest.approx(h, rel=1e-12) and sol.residual < 1e-12
    # h = M g at the mass centre, h -> inf at the leader's hand.
    assert line.force(line.sigma_of(rc)) == pytest.approx(M * G, rel=1e-12)
    assert line.point(line.sigma_inf) == pytest.approx(R1, abs=1e-15)
    np.testing.assert_allclose(line.mass_centre, rc)


def _R_x_up() -> np.ndarray:
    """Object x along world z (up), as in the paper's Fig. 4 and the PUMA beam."""
    return np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])


def _contact(rc: Any = (0.0, 0.0, 0.25), box: dict[str, Any] | None = None) -> SupportContact:
    b = box or {"r_min": (0.0, 0.0, 0.0), "r_max": (0.0, 0.0, 0.4)}
    return SupportContact(mass=4.0, mass_centre=rc, gravity=[0.0, 0.0, -G],
                          plane=PlaneBar(**b), H1=np.eye(4))


def test_turning_object_moves_the_support_line_as_gravity_predicts() -> None:
    contact = _contact()
    R0 = _R_x_up()
    line0 = contact.line(R0)
    np.testing.assert_allclose(contact.gravity_in_object(R0), [-G, 0, 0], atol=1e-15)
    np.testing.assert_allclose(line0.tangent(0.0), [0, 0, 1], atol=1e-15)
    # Predicted push (moment about the leader's hand at the origin): h z = M |g_x| 0.25.
    for z in (0.1, 0.25, 0.4):
        assert contact.force(line0, z) == pytest.approx(4.0 * G * 0.25 / z, rel=1e-12)
    # Turning about object x keeps g_x: the same line and the same forces.
    R_spin = R0 @ pin.exp3(np.array([0.7, 0.0, 0.0]))
    spun = contact.line(R_spin)
    np.testing.assert_allclose(spun.pose(0.0), line0.pose(0.0), atol=1e-15)
    assert spun.force(0.3) == pytest.approx(line0.force(0.3), rel=1e-12)
    # Tilting object x away from up by theta: g_o = R^T g has g_x = -g cos(theta). The
    # line (Eq. 9 about the mass centre) is fixed in the object while g_x keeps its sign,
    # and the push at every point scales with |g_x|.
    for theta in (0.3, 1.0, 1.4):
        R_tilt = R0 @ pin.exp3(np.array([0.0, theta, 0.0]))
        g_o = contact.gravity_in_object(R_tilt)
        assert g_o[0] == pytest.approx(-G * math.cos(theta), rel=1e-12)
        tilted = contact.line(R_tilt)
        np.testing.assert_allclose(tilted.pose(0.0), line0.pose(0.0), atol=1e-12)
        for z in (0.1, 0.4):
            assert contact.force(tilted, z) == pytest.approx(
                4.0 * G * math.cos(theta) * 0.25 / z, rel=1e-9)
    # x horizontal: the push carries none of the weight.
    with pytest.raises(InvalidInputError, match="no component along the object's x axis"):
        contact.line(R0 @ pin.exp3(np.array([0.0, math.pi / 2, 0.0])))
    # Upside down on this bar: pushing supports would lie behind the leader (z < 0),
    # outside the bar; the follower would have to pull.
    upside_down = R0 @ pin.exp3(np.array([0.0, math.pi, 0.0]))
    with pytest.raises(InvalidInputError, match=r"support lost.*h > 0"):
        contact.line(upside_down)
    # On a bar that extends behind the leader the line reverses: the pushing half-line
    # is now z < 0, where g_x > 0 and the follower presses down as a lever.
    long = _contact(box={"r_min": (0.0, 0.0, -0.4), "r_max": (0.0, 0.0, 0.4)})
    flipped = long.line(upside_down)
    np.testing.assert_allclose(flipped.tangent(0.0), [0, 0, -1], atol=1e-12)
    assert flipped.sigma_min == pytest.approx(0.0, abs=1e-12)  # from the leader's hand
    assert flipped.point(0.2)[2] == pytest.approx(-0.2, abs=1e-12)
    assert long.force(flipped, 0.2) == pytest.approx(4.0 * G * 0.25 / 0.2, rel=1e-9)
    with pytest.raises(InvalidInputError, match="support lost at grasp"):
        long.force(long.line(R0), -0.1)


def test_support_contact_checks() -> None:
    with pytest.raises(InvalidInputError, match="mass"):
        SupportContact(mass=0.0, mass_centre=(0, 0, 0), gravity=[0, 0, -G],
                       plane=PlaneBar(), H1=np.eye(4))
    with pytest.raises(InvalidInputError, match="gravity"):
        SupportContact(mass=1.0, mass_centre=(0, 0, 0), gravity=[0, 0, 0],
                       plane=PlaneBar(), H1=np.eye(4))
    with pytest.raises(InvalidInputError, match="PlaneBar"):
        SupportContact(mass=1.0, mass_centre=(0, 0, 0), gravity=[0, 0, -G],
                       plane=CylinderSurface(0.05), H1=np.eye(4))  # type: ignore[arg-type]
    # The leader's hand in object coordinates is the translation of H1^-1.
    H1 = np.eye(4)
    H1[:3, 3] = (0.0, 0.0, 0.1)
    c = SupportContact(mass=1.0, mass_centre=(0, 0, 0), gravity=[0, 0, -G],
                       plane=PlaneBar(), H1=H1)
    np.testing.assert_allclose(c.r1, [0.0, 0.0, -0.1])


def test_place_follower_equals_a_fresh_model() -> None:
    arm = puma560()
    H1 = np.eye(4)
    first = PlaneBar(r_min=(0, -1, -1), r_max=(0, 1, 1))
    other = PlaneBar(origin=(0.0, 0.05, 0.02), sliding=(0.0, 0.6, 0.8), r_min=(0, -1, -1),
                     r_max=(0, 1, 1))
    model = CarryModel(arm, first, H1)
    q = np.array([0.3, -0.4, 0.2, 0.1, 0.5, -0.2])
    before = model.update(q, 0.1)
    model.place_follower(other)
    after = model.update(q, 0.1)
    fresh = CarryModel(arm, other, H1).update(q, 0.1)
    assert not np.allclose(before.T_target, after.T_target)
    np.testing.assert_allclose(after.T_target, fresh.T_target, atol=1e-15)
    np.testing.assert_allclose(after.J_target, fresh.J_target, atol=1e-15)
    np.testing.assert_allclose(after.T_target, after.T_object @ other.pose(0.1), atol=1e-14)
    with pytest.raises(InvalidInputError, match="revolute"):
        model.place_follower(CurvedBar(0.5, sigma_min=-0.1, sigma_max=0.1))


def _beam_support_task() -> Experiment:
    path = Path(__file__).resolve().parents[2] / "configs" / "puma_beam_support.yaml"
    return build_experiment(load_config(path), str(path))


def test_builder_puts_the_follower_on_the_support_line_and_records_h() -> None:
    exp = _beam_support_task()
    task, s0 = exp.task, exp.initial
    opts = StepOptions(dt=0.031, joint_weights=np.ones(1), grasp_weight=100.0)
    line = task.surface
    # Start the builder on another path: its first step re-places the follower's joint
    # on the support line of the object's orientation.
    off = PlaneBar(origin=(0.0, 0.0, 0.03), r_min=(0, 0, 0), r_max=(0, 0, 0.4))
    builder = StepBuilder(replace(task, surface=off), opts)
    b = builder.build(s0)
    np.testing.assert_allclose(b.carry.T_target, b.carry.T_object @ line.pose(s0.sigma),
                               atol=1e-14)
    assert b.support_force == pytest.approx(4.0 * G * 0.25 / s0.sigma, rel=1e-12)
    ref = StepBuilder(task, opts).build(s0)
    np.testing.assert_allclose(b.problem.A, ref.problem.A, atol=1e-14)
    # The errors and the right-hand side are those of the re-placed target.
    np.testing.assert_allclose(b.closure_error, ref.closure_error, atol=1e-14)
    np.testing.assert_allclose(b.problem.b, ref.problem.b, atol=1e-12)
    assert np.abs(b.closure_error).max() < 1e-9  # the start closes the grasp on the line
    # A grasp records no force.
    grasp = StepBuilder(replace(task, contact=None), opts).build(s0)
    assert math.isnan(grasp.support_force)
    # A state whose grasp is behind the leader's hand needs a pull: the step refuses.
    with pytest.raises(InvalidInputError, match="support lost at grasp"):
        builder.build(DualArmState(s0.t, s0.q_l, s0.q_f, -0.01))
    # Turning the object upside down loses the support.
    q_l = s0.q_l.copy()
    q_l[5] += math.pi  # spins the hand about its approach (world x): object x goes down
    with pytest.raises(InvalidInputError, match="support lost"):
        builder.build(DualArmState(s0.t, q_l, s0.q_f, s0.sigma))


def test_the_compiled_line_is_the_contacts_line() -> None:
    """The kernel's line (what each step computes) is SupportContact.line's, to rounding,
    at random orientations; where the contact has no line, the kernel holds none. The
    bar of the beam (its pushing side lost upside down) and a wide face with the mass
    centre off the bar's axis (a sloped line)."""
    held = lost = 0
    rng = np.random.default_rng(11)
    for contact in (_contact(), _contact(rc=(0.0, 0.05, 0.25), box={
            "r_min": (0.0, -0.3, -0.4), "r_max": (0.0, 0.3, 0.4)})):
        plane = contact.compiled()
        for _ in range(100):
            R = _R_x_up() @ pin.exp3(rng.normal(0.0, 1.2, 3))
            line = plane.line(R)
            try:
                ref = contact.line(R)
            except InvalidInputError:
                assert not line.held
                lost += 1
                continue
            assert line.held
            held += 1
            np.testing.assert_allclose(line.gravity, contact.gravity_in_object(R), atol=1e-14)
            np.testing.assert_allclose(line.origin, ref.origin, atol=1e-15)
            np.testing.assert_allclose(line.direction, ref.tangent(0.0), atol=1e-15)
            np.testing.assert_allclose(line.pose0, ref.pose(0.0), atol=1e-15)
            for mine, theirs in ((line.sigma_min, ref.sigma_min),
                                 (line.sigma_max, ref.sigma_max),
                                 (line.sigma_inf, ref.sigma_inf)):
                assert mine == pytest.approx(theirs, rel=1e-14, abs=1e-15)
            for sigma in np.linspace(ref.sigma_min, ref.sigma_max, 5):
                assert line.push(sigma) == pytest.approx(ref.force(sigma), rel=1e-12)
    assert held > 100 and lost > 20


def test_a_support_step_makes_its_python_line_only_when_read(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """Each step's line comes from the kernel: the contact's Python line is made for a
    step only when its context's surfaces are read (and then it is that step's line)."""
    exp = _beam_support_task()
    builder = exp.controller().builder
    made: list[np.ndarray] = []
    python_line = SupportContact.line

    def counted(self: SupportContact, R: Any) -> Any:
        made.append(np.array(R))
        return python_line(self, R)

    monkeypatch.setattr(SupportContact, "line", counted)
    s0 = exp.initial
    builds = [builder.build(DualArmState(s0.t, s0.q_l + 0.01 * k, s0.q_f, s0.sigma))
              for k in range(3)]
    assert made == []
    surfaces = builds[1].context.surfaces
    assert len(made) == 1 and builds[1].context.surfaces is surfaces
    R = builds[1].carry.T_object[:3, :3]
    np.testing.assert_array_equal(made[0], R)
    np.testing.assert_allclose(surfaces[0].pose(0.0), python_line(exp.task.contact, R).pose(0.0),
                               atol=0.0)
