"""The physics check in MuJoCo: the static hold, the closed loop, a lagged follower."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from dualarm_qp.control.rollout import rollout
from dualarm_qp.experiments import build_experiment, load_config
from dualarm_qp.physics.check import PhysicsRun, closed_loop, closed_loop_limits, replay, verdict
from dualarm_qp.physics.plant import MujocoPlant
from dualarm_qp.physics.settings import PhysicsSettings

pytest.importorskip("mujoco", reason="the physics check needs MuJoCo "
                                     "(pip install -e '.[physics]'; '.[dev]' has it)")

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
BEAM = CONFIGS / "puma_beam_limits.yaml"


@pytest.fixture(scope="module")
def beam():
    return build_experiment(load_config(BEAM), str(BEAM))


@pytest.fixture(scope="module")
def beam_trace(beam):
    result = rollout(beam.controller(), beam.initial, duration=beam.duration,
                     limits=beam.limits)
    assert result.completed
    return result.trace


def test_the_hands_hold_the_weight_at_rest(beam):
    """Held still, the two welds carry the object's weight, the follower from below."""
    plant = MujocoPlant(beam.task, PhysicsSettings(object_mass=5.0))
    plant.reset(beam.initial, beam.options.dt)
    w_l, w_f, _, _ = plant.wrenches()
    up = w_l[:3] + w_f[:3]
    carried = plant.physics.carried  # the object and its slide chain (0.2 kg)
    assert carried == pytest.approx(5.2)
    np.testing.assert_allclose(up, [0.0, 0.0, carried * 9.81], atol=1e-3 * carried * 9.81)
    assert plant.log["support"][0] > 0.0  # the follower carries a share, pushing up
    assert plant.log["deviation_pos"][0] < 1e-4  # the servos hold the start under load


def test_without_the_load_feed_forward_the_servos_sag(beam, monkeypatch):
    """The load feed-forward is what keeps the start on D(t0): kp alone lets it sag."""
    settings = PhysicsSettings(object_mass=20.0)
    held = MujocoPlant(beam.task, settings)
    held.reset(beam.initial, beam.options.dt)

    def no_load(self, state):
        self._ff = np.zeros(self._arm_dofs.size)

    monkeypatch.setattr(MujocoPlant, "_feedforward", no_load)
    sagged = MujocoPlant(beam.task, settings)
    sagged.reset(beam.initial, beam.options.dt)
    assert sagged.log["deviation_pos"][0] > 5 * held.log["deviation_pos"][0]


@pytest.mark.slow
def test_the_beam_in_closed_loop_stays_on_its_path(beam):
    settings = PhysicsSettings()
    run = closed_loop(beam, settings)
    s = run.summary()
    assert run.result is not None and run.result.completed, run.result.message
    assert s["samples"] == 501
    assert s["deviation_pos_max_m"] < beam.limits.tracking[0]  # 1 mm
    assert s["slip_max_m"] < settings.slip_max
    assert s["follower_support_min_N"] > 0.0


def test_a_delayed_measurement_does_not_count_the_commanded_sliding_as_slip(beam):
    """With delay the controller plans from a sample-old state; the grasp still slides
    as commanded, so the slip stays well under one sample's sliding."""
    short = dataclasses.replace(beam, duration=1.0)
    runs = {delay: closed_loop(short, PhysicsSettings(), delay=delay) for delay in (False, True)}
    for run in runs.values():
        assert run.result is not None and run.result.completed
    step = float(np.abs(np.diff(runs[True].log["sigma"])).max())
    assert step > 2e-3  # the grasp slides: over 2 mm in a sample
    assert runs[True].summary()["slip_max_m"] < 0.1 * step
    assert runs[True].summary()["slip_max_m"] < 2 * runs[False].summary()["slip_max_m"]


def test_hands_off_their_grasps_are_a_divergence(beam, monkeypatch):
    """The weld guard: an error beyond WELD_ERROR_DIVERGED stops the simulation."""
    from dualarm_qp.physics.plant import DivergedError

    monkeypatch.setattr("dualarm_qp.physics.plant.WELD_ERROR_DIVERGED", 1e-9)
    plant = MujocoPlant(beam.task, PhysicsSettings())
    with pytest.raises(DivergedError, match=r"off its grasp.*lower physics\.servo_frequency"):
        plant.reset(beam.initial, beam.options.dt)


def test_a_closed_loop_the_preflight_refuses_still_records_its_start():
    """The rollout skips the plant's reset then; the check records the start itself."""
    path = CONFIGS / "puma_beam_leader_near_singular.yaml"  # a waypoint out of reach
    exp = build_experiment(load_config(path), str(path))
    run = closed_loop(exp, PhysicsSettings())
    assert run.result is not None and run.result.failure is not None
    assert run.result.failure.criterion == "unreachable"
    assert run.summary()["samples"] == 1
    assert verdict(run, None, PhysicsSettings())[0] == "stopped"


def test_the_largest_torque_reported_is_the_peak_the_ratio_reads(beam):
    """torque_max_N_m is each joint's peak over the substeps, as torque_ratio_max."""
    short = dataclasses.replace(beam, duration=0.5)
    settings = PhysicsSettings(tau_max={"leader": np.full(6, 200.0),
                                        "follower": np.array([150.0, 150, 150, 20, 20, 20])})
    s = closed_loop(short, settings).summary()
    ratio = np.r_[np.asarray(s["torque_max_N_m"]["leader"]) / 200.0,
                  np.asarray(s["torque_max_N_m"]["follower"]) / [150, 150, 150, 20, 20, 20]]
    assert s["torque_ratio_max"] > 0.05
    assert ratio.max() == pytest.approx(s["torque_ratio_max"], rel=1e-12)


@pytest.mark.slow
def test_a_lagged_follower_squeezes_more_than_the_rigid_replay(beam, beam_trace):
    tr, settings = beam_trace, PhysicsSettings()
    base = replay(beam, settings, tr.t, tr.q_l, tr.q_f, tr.tau, tr.grasp)
    lagged = replay(beam, settings, tr.t, tr.q_l, tr.q_f, tr.tau, tr.grasp, lag_follower=1)
    b, g = base.summary(), lagged.summary()
    assert g["internal_force_max_N"] > b["internal_force_max_N"] + 5.0
    # Three samples (93 ms) late: squeezed beyond the default threshold.
    late = replay(beam, settings, tr.t, tr.q_l, tr.q_f, tr.tau, tr.grasp, lag_follower=3)
    status, reasons = verdict(late, base, settings)  # the verdict reads the log only
    assert status == "squeezed" and "above the rigid replay" in reasons[0]


def test_the_verdict_orders_its_reasons():
    """The worst status wins; every reason is kept."""
    settings = PhysicsSettings()
    n = 4
    log = {k: np.zeros(n) for k in ("t", "deviation_pos", "deviation_rot", "internal",
                                    "support", "slip", "weld_leader", "weld_follower", "gap",
                                    "torque_ratio_peak")}
    log["torque"] = log["torque_peak"] = np.zeros((n, 12))
    limits = {"leader": np.full(6, np.inf), "follower": np.full(6, np.inf)}
    base = PhysicsRun("replay", {k: v.copy() for k, v in log.items()}, 0.0, [], limits)
    assert verdict(PhysicsRun("closed_loop", log, 0.0, [], limits), base, settings) == ("ok", [])
    log["internal"][2] = 25.0
    assert verdict(PhysicsRun("closed_loop", log, 0.0, [], limits), base, settings)[0] == \
        "squeezed"
    log["torque_ratio_peak"][1] = 1.5
    assert verdict(PhysicsRun("closed_loop", log, 0.0, [], limits), base, settings)[0] == "torque"
    log["slip"][3] = 0.006
    assert verdict(PhysicsRun("closed_loop", log, 0.0, [], limits), base, settings)[0] == \
        "slipped"
    log["deviation_pos"][3] = 0.02
    status, reasons = verdict(PhysicsRun("closed_loop", log, 0.0, [], limits), base, settings)
    assert status == "dropped" and len(reasons) == 4


def test_a_turned_object_is_dropped_and_the_closed_loop_runs_to_the_thresholds():
    from dualarm_qp.control.rollout import RunLimits
    from dualarm_qp.physics.check import closed_loop_limits

    settings = PhysicsSettings(deviation_max=0.02, rotation_max=0.1, slip_max=0.004)
    wide = closed_loop_limits(RunLimits(), settings)
    assert wide.tracking == (0.02, 0.1) and wide.closure == (0.004, 0.1)
    tight = closed_loop_limits(RunLimits(tracking=(0.05, 0.2)), settings)
    assert tight.tracking == (0.05, 0.2)  # never narrower than the run's own
    n = 3
    log = {k: np.zeros(n) for k in ("t", "deviation_pos", "deviation_rot", "internal",
                                    "support", "slip", "weld_leader", "weld_follower", "gap",
                                    "torque_ratio_peak")}
    log["torque"] = log["torque_peak"] = np.zeros((n, 12))
    limits = {"leader": np.full(6, np.inf), "follower": np.full(6, np.inf)}
    log["deviation_rot"][1] = 0.15
    status, reasons = verdict(PhysicsRun("closed_loop", log, 0.0, [], limits), None, settings)
    assert status == "dropped" and "turned" in reasons[0]


@pytest.mark.slow
def test_integrated_references_wind_the_squeeze_up(beam):
    """Integrated position references of two arms on one object drift apart unseen.

    The kinematic controller sees the measured joints, which the welds keep consistent;
    the references' disagreement only shows as internal force. Starting each sample's
    reference at the measured joints (the default) removes it.
    """
    measured = closed_loop(beam, PhysicsSettings(reference="measured")).summary()
    integrated = closed_loop(beam, PhysicsSettings(reference="integrated")).summary()
    assert measured["completed"] and integrated["completed"]
    # measured with the per-joint servo gains: 5.1 N against 1.1 N
    assert integrated["internal_force_max_N"] > 3.0 * measured["internal_force_max_N"]


@pytest.mark.parametrize(("delay", "predict"), [(0, True), (2, False), (2, True)])
def test_the_controller_is_handed_the_measurement_delay_samples_late(beam, delay, predict):
    """State and reading k are those the plant measured at sample k - delay (the start's
    before that); with ``predict`` the state is brought forward by the commands since."""
    short = dataclasses.replace(beam, duration=0.31)
    plant = MujocoPlant(beam.task, PhysicsSettings(delay=delay, predict=predict))
    result = rollout(short.controller(), short.initial, duration=short.duration,
                     limits=closed_loop_limits(short.limits, plant.settings), plant=plant)
    assert result.completed
    tr, log, dt = result.trace, plant.arrays(), short.options.dt
    n = len(tr)
    assert len(plant.readings) == n == log["t"].size
    for k in range(1, n):
        late = max(k - delay, 0)
        np.testing.assert_array_equal(plant.readings[k].leader, log["w_leader"][late])
        np.testing.assert_array_equal(plant.readings[k].follower, log["w_follower"][late])
        since = range(max(late, k - delay), k) if predict and late else range(0)
        if late:
            expected = log["sigma"][late] + sum(dt * tr.m[j] for j in since)
            assert tr.grasp[k] == pytest.approx(expected, abs=1e-15)
