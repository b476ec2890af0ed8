"""What the simulation saw first: the cause of a physics verdict, on made-up logs."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from dualarm_qp.control.rollout import Failure
from dualarm_qp.physics.cause import first_cause, threshold_events
from dualarm_qp.physics.check import PhysicsRun, diagnose, physics_summary
from dualarm_qp.physics.settings import PhysicsSettings

N = 20  # controller samples of 31 ms
SUBSTEPS = 31
H = 1e-3
JOINTS = [f"leader.joint{i}" for i in range(1, 7)] + [f"follower.joint{i}" for i in range(1, 7)]
PLAN_DIAGNOSIS = ("cause: tolerance: one step of 0.031 s at these speeds leaves a "
                  "second-order error beyond the tolerance")


def _log(n: int = N) -> dict[str, np.ndarray]:
    log = {k: np.zeros(n) for k in ("deviation_pos", "deviation_rot", "internal", "support",
                                    "slip", "weld_leader", "weld_follower", "gap",
                                    "torque_ratio_peak")}
    log["t"] = np.arange(n) * 0.031
    log["torque"] = np.zeros((n, 12))
    log["torque_peak"] = np.zeros((n, 12))
    return log


def _stopped(k: int) -> SimpleNamespace:
    """A rollout the controller stopped at sample ``k`` on the closure, explained from
    the plan's kinematics as the rollout does."""
    message = (f"step {k} at t = {k * 0.031:.4f} s: grasp closure lost: 0.00507 m, "
               f"0.00637 rad (tolerance 0.005 m, 0.05 rad); {PLAN_DIAGNOSIS}")
    failure = Failure("closure", k, k * 0.031, 0.00507, 0.005, message)
    return SimpleNamespace(completed=False, message=message, failure=failure,
                           path_completed=k / N)


def _run(log: dict[str, np.ndarray], velocity_error: np.ndarray | None = None,
         result: SimpleNamespace | None = None, name: str = "closed_loop") -> PhysicsRun:
    limits = {"leader": np.full(6, 10.0), "follower": np.full(6, 20.0)}
    n = log["t"].size
    error = (np.zeros(((n - 1) * SUBSTEPS, 12)) if velocity_error is None
             else velocity_error)
    return PhysicsRun(name, log, 0.0, [], limits, result, (0.0, "", 0.0), JOINTS, error,
                      H, SUBSTEPS)


def _growing_error(onset_s: float) -> np.ndarray:
    """Follower joint 3 rings at 80 Hz from ``onset_s`` on, growing 20-fold a tenth of a
    second; every other joint is quiet."""
    t = np.arange((N - 1) * SUBSTEPS) * H
    error = np.zeros((t.size, 12))
    grow = np.where(t < onset_s, 0.0, 0.01 * np.exp(30.0 * (t - onset_s)))
    error[:, 8] = grow * np.sin(2.0 * np.pi * 80.0 * (t - onset_s))
    return error


def test_a_stop_after_a_growing_oscillation_names_the_oscillation_not_the_plan():
    settings = PhysicsSettings()
    base = _run(_log(), name="replay")
    closed = _run(_log(17), _growing_error(0.2)[:16 * SUBSTEPS], _stopped(16))
    judged = diagnose(closed, base, settings)
    assert judged.status == "stopped"
    assert judged.cause is not None and judged.cause.kind == "oscillation"
    assert judged.cause.sample == 7 and judged.cause.t == pytest.approx(0.2, abs=0.01)
    assert "oscillated at 80 Hz" in judged.message and "follower.joint3" in judged.message
    assert "then the controller stopped the closed loop: step 16" in judged.message
    assert "second-order" not in judged.message  # not the plan's kinematics
    assert not any("second-order" in r for r in judged.reasons)
    section = physics_summary(closed, base, settings)
    assert section["status"] == "stopped" and section["cause"] == "oscillation"
    assert section["cause_sample"] == 7 and section["message"] == judged.message
    assert section["oscillation"]["largest_joint"] == "follower.joint3"
    assert section["oscillation"]["frequency_hz"] == pytest.approx(80.0, rel=0.05)


def test_a_stop_with_nothing_seen_in_the_simulation_keeps_the_plans_explanation():
    closed = _run(_log(17), result=_stopped(16))
    judged = diagnose(closed, _run(_log(), name="replay"), PhysicsSettings())
    assert judged.status == "stopped" and judged.oscillation is None
    assert judged.cause is not None and judged.cause.kind == "controller"
    assert judged.cause.sample == 16
    assert "second-order" in judged.message  # the plan's own error is what grew


def test_a_torque_over_its_limit_names_the_joint_the_amount_and_when():
    log = _log()
    log["torque_peak"][5:, 9] = 30.0  # follower joint 4: 1.5 of its 20 N m from sample 5
    log["torque_ratio_peak"][5:] = 1.5
    log["internal"][12] = 50.0  # a squeeze later on does not take the blame
    judged = diagnose(_run(log), _run(_log(), name="replay"), PhysicsSettings())
    assert judged.status == "torque" and judged.cause is not None
    assert (judged.cause.kind, judged.cause.sample) == ("torque", 5)
    assert judged.cause.t == pytest.approx(5 * 0.031)
    assert "follower.joint4 passed its torque limit" in judged.message
    assert "30 N m, 1.5 of its 20 N m" in judged.message


def test_each_threshold_is_dated_where_it_was_first_passed():
    log = _log()
    log["internal"][[4, 9]] = [15.0, 40.0]  # the replay peaks at 10 N: squeezed from 9
    log["slip"][11] = 0.006
    log["deviation_pos"][14] = 0.02
    base = _log()
    base["internal"][3] = 10.0
    events = threshold_events(_run(log), 10.0, PhysicsSettings())
    assert {e.kind: e.sample for e in events} == {"squeezed": 9, "slipped": 11, "dropped": 14}
    squeezed = next(e for e in events if e.kind == "squeezed")
    assert "40.0 N, 30.0 N above the rigid replay's peak" in squeezed.message
    judged = diagnose(_run(log), _run(base, name="replay"), PhysicsSettings())
    assert judged.status == "dropped" and judged.cause is not None
    assert judged.cause.kind == "squeezed"
    assert judged.message.endswith("then: the object left D(t) by 20.00 mm "
                                   "(deviation_max 10 mm)")


def test_on_one_sample_the_oscillation_comes_before_what_it_leads_to():
    log = _log()
    log["internal"][1] = 100.0
    events = threshold_events(_run(log), 0.0, PhysicsSettings())
    closed = _run(log, _growing_error(0.0))
    oscillation = diagnose(closed, None, PhysicsSettings()).oscillation
    assert oscillation is not None and oscillation.sample == events[0].sample == 1
    cause = first_cause([*events, oscillation])
    assert cause is not None and cause.kind == "oscillation"


def test_an_ok_run_has_no_cause():
    judged = diagnose(_run(_log()), _run(_log(), name="replay"), PhysicsSettings())
    assert (judged.status, judged.cause, judged.message) == ("ok", None, "")
