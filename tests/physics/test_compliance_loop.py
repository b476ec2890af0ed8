"""The compliant follower and a late measurement in MuJoCo's closed loop."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
import yaml

from dualarm_qp.errors import ConfigError
from dualarm_qp.experiments import build_experiment, load_config, parse_config
from dualarm_qp.kinematics.robots import example_robots_dir
from dualarm_qp.physics.check import closed_loop, diagnose
from dualarm_qp.physics.command import settings_of
from dualarm_qp.physics.compliance import ComplianceGains
from dualarm_qp.physics.settings import PhysicsSettings

pytest.importorskip("mujoco", reason="the physics check needs MuJoCo "
                                     "(pip install -e '.[physics]'; '.[dev]' has it)")

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
BEAM = CONFIGS / "puma_beam_limits.yaml"
HEAVY = CONFIGS / "ur5_pair_heavy_bar.yaml"
needs_robots = pytest.mark.skipif(example_robots_dir() is None,
                                  reason="example-robot-data is not installed")


def _experiment(path: Path):
    cfg = load_config(path)
    return build_experiment(cfg, str(path)), settings_of(cfg)


@pytest.mark.parametrize(("given", "gains"), [
    (True, ComplianceGains()), (False, None),
    ({"force_gain": 1e-3, "filter_time": 0.05}, ComplianceGains(1e-3, 2e-3, 0.05))])
def test_the_files_compliance_section(given, gains):
    data = yaml.safe_load(BEAM.read_text())
    data["physics"] = {"compliance": given}
    s = PhysicsSettings.from_spec(parse_config(data, "beam.yaml").physics, 1e-3)
    assert s.compliance == gains
    assert s.as_dict()["compliance"] == (None if gains is None else gains.as_dict())


def test_a_bad_compliance_gain_names_its_key():
    data = yaml.safe_load(BEAM.read_text())
    data["physics"] = {"compliance": {"force_gain": -1}}
    with pytest.raises(ConfigError, match=r"physics\.compliance\.force_gain"):
        parse_config(data, "beam.yaml")


def test_without_prediction_a_late_measurement_makes_the_loop_ring():
    """Two samples late, the feedback acts on errors it has already corrected: the
    object leaves D(t) within half a second; brought forward by the commands since, the
    same loop carries it."""
    exp, settings = _experiment(BEAM)
    short = dataclasses.replace(exp, duration=0.62)
    late = closed_loop(short, dataclasses.replace(settings, delay=2, predict=False))
    assert diagnose(late, None, settings).status in ("dropped", "stopped")
    predicted = closed_loop(short, dataclasses.replace(settings, delay=2))
    assert predicted.result is not None and predicted.result.completed
    assert predicted.summary()["deviation_pos_max_m"] < 1e-3


@pytest.mark.slow
def test_the_beam_three_samples_late_squeezes_under_30_n():
    exp, settings = _experiment(BEAM)
    for gains in (None, ComplianceGains()):
        run = closed_loop(exp, dataclasses.replace(settings, delay=3, compliance=gains))
        s = run.summary()
        assert run.result is not None and run.result.completed, run.result.message
        assert s["internal_force_max_N"] < 30.0
        assert diagnose(run, None, settings).oscillation is None


@pytest.mark.slow
@needs_robots
def test_the_heavy_bar_keeps_its_split_and_torque_only_with_the_compliant_follower():
    """The file's closed loop (compliance on): verdict ok, every torque within the
    stated allowance, each hand's share within 10% of the plan's; the same loop with
    the standard closure breaks the shoulder's limit."""
    exp, settings = _experiment(HEAVY)
    assert settings.compliance is not None and settings.torque_ratio_max == 1.02
    run = closed_loop(exp, settings)
    judged = diagnose(run, None, settings)
    s = run.summary()
    assert judged.status == "ok", judged.message
    assert s["torque_ratio_max"] <= 1.02
    assert s["split_error_max"] < 0.10
    settled = run.log["split_error"][10:]  # after the first 0.1 s
    assert np.nanmax(settled) < 0.05
    stiff = closed_loop(exp, dataclasses.replace(settings, compliance=None))
    assert stiff.summary()["torque_ratio_max"] > 1.05
    assert np.nanmax(stiff.log["split_error"][10:]) > 2 * np.nanmax(settled)


def _support_error(run) -> np.ndarray:
    """|measured - planned| support force [N] per sample: the plan's share of what the
    two hands measured along the support's normal, against the support's own."""
    g = run.log
    support, share = np.asarray(g["support"]), np.asarray(g["share"])
    planned = np.asarray(g["share_plan"]) * support / share
    return np.abs(support - planned)


@pytest.mark.slow
def test_a_compliant_support_pushes_with_the_plans_force():
    """Case 2: the compliant follower regulates its normal force to the support line's;
    the standard closure leaves it where the servos' stiffness puts it."""
    exp, settings = _experiment(CONFIGS / "puma_beam_support.yaml")
    stiff = closed_loop(exp, dataclasses.replace(settings, compliance=None))
    compliant = closed_loop(exp, dataclasses.replace(settings, compliance=ComplianceGains()))
    for run in (stiff, compliant):
        assert run.result is not None and run.result.completed, run.result.message
    assert np.nanmedian(_support_error(stiff)) > 8.0
    assert np.nanmax(_support_error(compliant)) < 4.0
