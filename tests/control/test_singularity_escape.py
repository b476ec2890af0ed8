"""Runs that start at an exact singularity leave it instead of stalling (status ESCAPING).

Each case starts an arm at an exact singular configuration of the wrist, the elbow or
the shoulder (a root of det J to rounding) and moves the object along the direction the
singular arm has lost (the sign that keeps the end in reach). A run whose task scale
collapses there takes an escape move inside every bound; without it the path stalls.
"""

from __future__ import annotations

import copy
from collections import Counter
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st

from dualarm_qp.control.escape import escape_move, sigma_gradient
from dualarm_qp.control.preflight import unreachable_waypoint
from dualarm_qp.control.rollout import rollout
from dualarm_qp.experiments import build_experiment
from dualarm_qp.experiments.config import parse_config
from dualarm_qp.kinematics.puma560 import puma560
from dualarm_qp.kinematics.robots import example_robot_arm
from dualarm_qp.solvers._affine import factor
from dualarm_qp.step.problem import StepProblem

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
PUMA = CONFIGS / "puma_beam_limits.yaml"
UR5 = CONFIGS / "ur5_pair_sliding_bar.yaml"
PUMA_FOLLOWER = [-150, 32.065, -30.9446, 0, -30, -105.8256]
UR5_FOLLOWER = [-21.3, -117.9, 130.0, -102.2, -90.0, 68.7]

#: (config, leader joints [deg], follower joints [deg], grasp [mm], singular arm).
#: Elbow and shoulder joints are roots of det J found by bisection (to 1e-15 rad).
CASES = {
    "puma-wrist": (PUMA, [0, -45, 160, 0, 0, 0], PUMA_FOLLOWER, 300, "leader"),
    "puma-elbow": (PUMA, [0, -45, 92.68639475436075, 0, 30, 0], PUMA_FOLLOWER, 300,
                   "leader"),
    "puma-shoulder": (PUMA, [0, -27.968704983327754, -30.9446, 0, 30, 0], PUMA_FOLLOWER,
                      300, "leader"),
    "ur5-wrist": (UR5, [-15.8, -101.1, 119.5, -108.4, 0.0, -105.8], UR5_FOLLOWER, 500,
                  "leader"),
    "ur5-elbow": (UR5, [-15.8, -101.1, 0.0, -108.4, -90.0, -105.8], UR5_FOLLOWER, 500,
                  "leader"),
    "ur5-shoulder": (UR5, [-15.8, 18.522710450768933, 130.0, -102.2, -60.0, 68.7],
                     UR5_FOLLOWER, 500, "leader"),
    # The case: a UR follower whose wrist starts at q5 = 0 (base: auto).
    "ur5-follower-wrist": (UR5, None, [-21.3, -117.9, 130.0, -102.2, 0.0, 68.7], 500,
                           "follower"),
}


def _pose(T: np.ndarray) -> dict:
    return {"position": (T[:3, 3] * 1e3).tolist(), "rotation": T[:3, :3].tolist()}


def singular_start(name: str, *, perturb_deg: float = 0.0, duration: float = 1.5):
    """The experiment of case ``name``: its arm singular at t0, the path along the
    direction that arm lost, 30 mm (or the rotation of 30 mm at 0.3 m) in reach."""
    cfg, lead, fol, grasp, arm = CASES[name]
    data = yaml.safe_load(cfg.read_text())
    data["controller"]["centre_horizon"] = 5.0  # no centring pull off the singularity
    data["controller"]["duration"] = duration
    data["object"]["grasp_initial"] = grasp
    for role in ("leader", "follower"):
        data[role].pop("q_min", None)
        data[role].pop("q_max", None)
    fol = list(fol)
    if arm == "follower":
        fol[4] += perturb_deg
    data["follower"]["base"] = "auto"
    data["follower"]["initial"] = {"joints": fol}
    probe = build_experiment(parse_config(copy.deepcopy(data), name), name)
    if lead is None:
        q_l, T0 = probe.initial.q_l, probe.task.trajectory.pose(0.0)
    else:
        lead = list(lead)
        lead[4] += perturb_deg
        q_l = np.deg2rad(lead)
        T0 = probe.task.leader.fk(q_l) @ probe.task.H1
        data["leader"]["initial"] = {"joints": lead}
    data["trajectory"] = {"type": "waypoints",
                          "waypoints": [{"t": 0, "pose": _pose(T0)},
                                        {"t": duration, "pose": _pose(T0)}]}
    if arm == "leader":
        u = np.linalg.svd(probe.task.leader.jacobian(q_l))[0][:, -1]
    else:
        placed = build_experiment(parse_config(copy.deepcopy(data), name), name)
        f, q_f = placed.task.follower, placed.initial.q_f
        u_f = np.linalg.svd(f.jacobian(q_f))[0][:, -1]
        w = u_f[3:]
        u = np.r_[u_f[:3] - np.cross(w, f.fk(q_f)[:3, 3] - T0[:3, 3]), w]
    for sign in (1.0, -1.0):
        v, w = sign * u[:3], sign * u[3:]
        k = 0.03 / max(float(np.linalg.norm(v)), 0.3 * float(np.linalg.norm(w)))
        T1 = T0.copy()
        T1[:3, :3] = pin.exp3(w * k) @ T0[:3, :3]
        T1[:3, 3] += v * k
        data["trajectory"]["waypoints"][1]["pose"] = _pose(T1)
        exp = build_experiment(parse_config(copy.deepcopy(data), name), name)
        if unreachable_waypoint(exp.task, exp.initial, duration, within_ranges=True) is None:
            return exp
    raise AssertionError(f"{name}: no direction in reach")


def run(exp, *, escape: bool = True):
    ctrl = exp.controller()
    if not escape:
        ctrl = type(ctrl)(exp.task, ctrl.solver, exp.options, leader_gain=exp.leader_gain,
                          policy=exp.policy, fallback=ctrl.fallback, singularity_escape=None,
                          error_budget=(0.5e-3, 5e-3))
    return rollout(ctrl, exp.initial, duration=exp.duration, limits=exp.limits)


@pytest.mark.parametrize("name", list(CASES))
def test_a_run_from_an_exact_singularity_completes(name: str) -> None:
    exp = singular_start(name)
    arm = exp.task.leader if CASES[name][4] == "leader" else exp.task.follower
    q0 = exp.initial.q_l if CASES[name][4] == "leader" else exp.initial.q_f
    assert np.linalg.svd(arm.jacobian(q0), compute_uv=False)[-1] < 1e-15  # exact
    res = run(exp)
    assert res.completed, res.message
    counts = Counter(res.trace.status)
    assert counts.get("error", 0) == 0


@pytest.mark.parametrize("name", ["puma-wrist", "ur5-wrist", "ur5-follower-wrist"])
def test_without_the_escape_the_same_run_stalls(name: str) -> None:
    """The cases whose lost direction no redundancy supplies: the escape is what helps."""
    exp = singular_start(name)
    stuck = run(exp, escape=False)
    assert stuck.failure is not None and stuck.failure.criterion == "stalled", stuck.message
    res = run(exp)
    assert res.completed, res.message
    assert "escaping" in res.trace.status
    sv = res.trace.sigma_min_l if CASES[name][4] == "leader" else res.trace.sigma_min_f
    assert sv[-1] > 1e-3  # left the singularity for good


@pytest.mark.parametrize("perturb_deg", [1e-9, -1e-9, 1e-6])
def test_a_perturbed_singular_start_completes_too(perturb_deg: float) -> None:
    res = run(singular_start("ur5-wrist", perturb_deg=perturb_deg))
    assert res.completed, res.message


@pytest.mark.parametrize("arm", [puma560(), example_robot_arm("ur5", "base_link", "tool0")],
                         ids=["puma", "ur5"])
@settings(max_examples=20, deadline=None)
@given(q=st.lists(st.floats(-3.0, 3.0), min_size=6, max_size=6))
def test_the_gradient_of_the_smallest_singular_value_matches_differences(arm, q) -> None:
    q = np.array(q)
    sigma, grad = sigma_gradient(arm, q)
    h = 1e-6
    for j in range(arm.n):
        dq = np.zeros(arm.n)
        dq[j] = h
        plus = np.linalg.svd(arm.jacobian(q + dq), compute_uv=False)[-1]
        minus = np.linalg.svd(arm.jacobian(q - dq), compute_uv=False)[-1]
        if min(plus, minus, sigma) < 1e-4:  # |f| kinks at zero: no derivative there
            continue
        assert grad[j] == pytest.approx((plus - minus) / (2 * h), abs=1e-6)


def test_an_escape_move_keeps_the_box_and_the_equality() -> None:
    """At a singular leader the move leaves the null space; at a singular follower with a
    free slide it stays in it. Either way every bound holds."""
    for name in ("ur5-wrist", "ur5-follower-wrist"):
        exp = singular_start(name)
        ctrl = exp.controller()
        build = ctrl._builder.build(exp.initial)
        problem: StepProblem = build.problem
        role = CASES[name][4]
        arms = (("leader", exp.task.leader, slice(0, 6), exp.initial.q_l) if role == "leader"
                else ("follower", exp.task.follower, slice(6, 12), exp.initial.q_f),)
        esc = escape_move(problem, np.zeros(problem.n), arms, 1e-3, exp.options.dt, 0.5e-3)
        assert esc is not None and esc.rate > 0.0
        assert np.all(esc.x >= problem.lower) and np.all(esc.x <= problem.upper)
        if esc.null_space:
            N = factor(problem.A).N
            assert np.linalg.norm(esc.x - N @ (N.T @ esc.x)) <= 1e-9 * np.linalg.norm(esc.x)
        else:  # the equality moves by at most a quarter of the budget in one sample
            drift = exp.options.dt * np.abs(problem.A @ esc.x).max()
            assert drift <= 0.25 * 0.5e-3 + 1e-15
