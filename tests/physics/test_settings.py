"""The ``physics:`` section of an experiment file (no simulator needed)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

from dualarm_qp.cli import main
from dualarm_qp.errors import ConfigError
from dualarm_qp.experiments.config import load_config, parse_config
from dualarm_qp.physics.settings import PhysicsSettings

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
BEAM = CONFIGS / "puma_beam_limits.yaml"


def _with_physics(physics: object) -> dict:
    data = yaml.safe_load(BEAM.read_text())
    data["physics"] = physics
    return data


def test_defaults_are_documented_values():
    s = PhysicsSettings.from_spec(load_config(BEAM).physics, 1e-3)
    assert (s.servo, s.reference, s.reference_time, s.kp, s.kv, s.armature, s.delay) == (
        "position", "measured", 0.03, None, None, 0.05, False)
    assert (s.servo_frequency, s.damping_ratio) == (40.0, 1.0)
    assert (s.deviation_max, s.slip_max, s.squeeze_max, s.torque_ratio_max) == (
        0.01, 0.005, 20.0, 1.0)


def test_lengths_follow_the_file_units_and_gains_stay_si():
    cfg = parse_config(_with_physics({"deviation_max": 4, "slip_max": 2, "kp": 5000,
                                      "rotation_max": 3, "reference_time": 0.5,
                                      "tau_max": {"leader": 80, "follower": [1, 2, 3, 4, 5, 6]}}),
                       "beam.yaml")
    s = PhysicsSettings.from_spec(cfg.physics, 1e-3, np.pi / 180, 1e-3)  # mm, deg, ms
    assert s.deviation_max == pytest.approx(0.004) and s.slip_max == pytest.approx(0.002)
    assert s.rotation_max == pytest.approx(np.radians(3)) and s.reference_time == 5e-4
    assert s.kp == 5000
    assert s.tau_max is not None
    np.testing.assert_array_equal(s.tau_max["leader"], [80.0])
    np.testing.assert_array_equal(s.tau_max["follower"], [1, 2, 3, 4, 5, 6])


@pytest.mark.parametrize(("physics", "key", "words"), [
    ({"servo": "torque"}, "physics.servo", "position, velocity"),
    ({"reference": "planned"}, "physics.reference", "measured, integrated"),
    ({"geometry": "hulls"}, "physics.geometry", "meshes, capsules"),
    ({"reference_time": 0}, "physics.reference_time", "> 0"),
    ({"kv": 0}, "physics.kv", "> 0"),
    ({"squeeze_max": -1}, "physics.squeeze_max", "> 0"),
    ({"servo": "position", "kp": 0}, "physics.kp", "kp > 0"),
    ({"delay": "yes"}, "physics.delay", ""),
    ({"tau_max": {"leader": [0, 1]}}, "physics.tau_max.leader", "> 0"),
    ({"gain": 3}, "physics.gain", "valid"),
])
def test_bad_values_name_the_file_and_the_key(physics, key, words):
    with pytest.raises(ConfigError) as err:
        parse_config(_with_physics(physics), "beam.yaml")
    text = str(err.value)
    assert "beam.yaml" in text and key in text and words in text


def test_the_geometry_defaults_to_meshes_and_is_reported():
    s = PhysicsSettings.from_spec(load_config(BEAM).physics, 1e-3)
    assert s.geometry == "meshes" and s.as_dict()["geometry"] == "meshes"
    cfg = parse_config(_with_physics({"geometry": "capsules"}), "beam.yaml")
    s = PhysicsSettings.from_spec(cfg.physics, 1e-3)
    assert s.geometry == "capsules" and s.as_dict()["geometry"] == "capsules"
    with pytest.raises(ValueError, match="geometry"):
        PhysicsSettings(geometry="hulls")


def test_a_bad_section_exits_2_from_the_command_line(tmp_path, capsys):
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(_with_physics({"servo": "torque"})))
    assert main(["run", str(path), "--out", str(tmp_path / "o"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "physics.servo" in err and str(path) in err and "Traceback" not in err


def test_the_package_and_a_config_load_without_mujoco():
    code = ("import sys, dualarm_qp, dualarm_qp.physics.settings, dualarm_qp.physics.mjcf; "
            "from dualarm_qp.experiments.config import load_config; "
            f"load_config({str(BEAM)!r}); "
            "assert 'mujoco' not in sys.modules, 'mujoco imported'")
    subprocess.run([sys.executable, "-c", code], check=True)


def test_without_mujoco_the_plant_says_how_to_install_it(tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "mujoco", None)  # import mujoco raises ImportError
    path = tmp_path / "beam.yaml"
    path.write_text(yaml.safe_dump(yaml.safe_load(BEAM.read_text())))
    code = main(["run", str(path), "--out", str(tmp_path / "o"), "--quiet", "--plant",
                 "mujoco"])
    err = capsys.readouterr().err
    assert code == 2 and 'pip install "dualarm-qp[physics]"' in err
    assert not (tmp_path / "o" / "summary.json").exists()


def test_torque_limits_take_the_arms_tau_max_after_the_physics_section():
    """physics.tau_max, else the controller's <arm>.tau_max, else the URDF's effort."""
    from dualarm_qp.experiments.setup import build_experiment
    from dualarm_qp.physics.check import arm_tau_max
    from dualarm_qp.physics.plant import torque_limits

    path = CONFIGS / "ur5_pair_heavy_bar.yaml"
    cfg = load_config(path)
    exp = build_experiment(cfg, str(path))
    effort = np.asarray(exp.task.follower.model.effortLimit, dtype=float)[:6]
    plain = PhysicsSettings.from_spec(cfg.physics, exp.options.dt)
    assert exp.options.follower_tau_max is not None
    lim = torque_limits(exp.task, plain, arm_tau_max(exp))
    np.testing.assert_array_equal(lim["follower"], exp.options.follower_tau_max)
    assert lim["follower"][1] < effort[1]  # the file halves the shoulder's limit
    np.testing.assert_array_equal(torque_limits(exp.task, plain)["follower"], effort)
    data = yaml.safe_load(path.read_text())
    data["physics"] = {"tau_max": {"follower": 40}}
    given = parse_config(data, "bar.yaml")
    own = PhysicsSettings.from_spec(given.physics, exp.options.dt)
    np.testing.assert_array_equal(torque_limits(exp.task, own, arm_tau_max(exp))["follower"],
                                  np.full(6, 40.0))


def test_a_physics_torque_limit_may_be_infinite():
    """``.inf`` leaves that joint without a limit, as ``<arm>.tau_max`` does."""
    from dualarm_qp.experiments.setup import build_experiment
    from dualarm_qp.physics.command import settings_for
    from dualarm_qp.physics.plant import torque_limits

    text = BEAM.read_text() + "\nphysics: {tau_max: {leader: [.inf, 90, 90, .inf, 20, 20]}}\n"
    path = "beam.yaml"
    cfg = parse_config(yaml.safe_load(text), path)
    exp = build_experiment(cfg, path)
    lim = torque_limits(exp.task, settings_for(cfg, exp, path))
    np.testing.assert_array_equal(lim["leader"], [np.inf, 90, 90, np.inf, 20, 20])


@pytest.mark.parametrize("config", ["puma_beam_limits.yaml", "ur5_pair_heavy_bar.yaml"])
def test_a_physics_torque_limit_needs_one_value_or_one_per_joint(config):
    from dualarm_qp.errors import InvalidInputError
    from dualarm_qp.experiments.setup import build_experiment
    from dualarm_qp.kinematics.robots import example_robots_dir
    from dualarm_qp.physics.command import settings_for
    from dualarm_qp.physics.plant import torque_limits

    if config.startswith("ur5") and example_robots_dir() is None:
        pytest.skip("example-robot-data is not installed")
    data = yaml.safe_load((CONFIGS / config).read_text())
    exp = build_experiment(parse_config(data, config), config)
    data["physics"] = {"tau_max": {"follower": [1, 2, 3]}}
    cfg = parse_config(data, config)
    for refuse in (lambda: build_experiment(cfg, config),  # at load, as run does
                   lambda: settings_for(cfg, exp, config)):
        with pytest.raises(ConfigError) as err:
            refuse()
        text = str(err.value)
        assert config in text and "physics.tau_max.follower" in text
        assert f"1 value (every joint) or {exp.task.follower.n}" in text
    with pytest.raises(InvalidInputError, match="follower: torque limits need 1 value"):
        torque_limits(exp.task, PhysicsSettings.from_spec(cfg.physics, 1e-3))


def test_the_modules_example_is_the_defaults_in_the_units_it_states():
    import dataclasses
    import re

    import dualarm_qp.physics.settings as module
    from dualarm_qp.experiments.config_physics import PhysicsSpec

    doc = module.__doc__ or ""
    units = yaml.safe_load(re.search(r"``units: (\{.*?\})``", doc).group(1))
    block = doc.split("    physics:\n", 1)[1].split("\n\n", 1)[0]
    example = {k: v for k, v in yaml.safe_load(block).items() if k != "tau_max"}
    scale = {"mm": 1e-3, "m": 1.0, "deg": np.pi / 180, "rad": 1.0, "ms": 1e-3, "s": 1.0}
    got = PhysicsSettings.from_spec(PhysicsSpec(**example), scale[units["length"]],
                                    scale[units["angle"]], scale[units["time"]])
    assert dataclasses.replace(got, tau_max=None) == PhysicsSettings()
    degrees = float(re.search(r"``rotation_max`` is ([0-9.]+)", doc).group(1))
    assert np.radians(degrees) == pytest.approx(PhysicsSettings().rotation_max, rel=2e-3)


@pytest.mark.parametrize(("given", "samples"), [(True, 1), (False, 0), (0, 0), (3, 3)])
def test_the_delay_is_a_number_of_samples_and_true_is_one(given, samples):
    cfg = parse_config(_with_physics({"delay": given}), "beam.yaml")
    s = PhysicsSettings.from_spec(cfg.physics, 1e-3)
    assert s.delay == samples and s.as_dict()["delay_samples"] == samples


@pytest.mark.parametrize("given", [-1, 1.5, "2", 101])
def test_a_delay_that_is_no_whole_number_of_samples_names_the_key(given):
    with pytest.raises(ConfigError) as err:
        parse_config(_with_physics({"delay": given}), "beam.yaml")
    assert "physics.delay" in str(err.value) and "whole number of samples" in str(err.value)
