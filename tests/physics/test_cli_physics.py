"""``dualarm-qp physics RUN_DIR`` and ``dualarm-qp run --plant mujoco``."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import yaml

from dualarm_qp.cli import main
from dualarm_qp.kinematics.robots import example_robots_dir

pytest.importorskip("mujoco", reason="the physics check needs MuJoCo "
                                     "(pip install -e '.[physics]'; '.[dev]' has it)")

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
BEAM = CONFIGS / "puma_beam_limits.yaml"


def _short_beam(tmp_path: Path, **physics) -> Path:
    data = yaml.safe_load(BEAM.read_text())
    data["controller"]["duration"] = 0.31  # 10 samples
    if physics:
        data["physics"] = physics
    path = tmp_path / "beam.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


@pytest.fixture
def short_run(tmp_path):
    out = tmp_path / "run"
    assert main(["run", str(_short_beam(tmp_path)), "--out", str(out), "--quiet",
                 "--no-plots"]) == 0
    return out


@pytest.mark.slow
def test_physics_adds_its_verdict_figure_and_report_section(short_run, capsys):
    assert main(["physics", str(short_run)]) == 0
    printed = capsys.readouterr().out
    summary = json.loads((short_run / "summary.json").read_text())
    physics = summary["physics"]
    assert physics["status"] == "ok" and f"physics.status: {physics['status']}" in printed
    assert printed.count("no torque limits") == 2 and "nan" not in printed  # the PUMA's
    for run in ("replay", "closed_loop"):
        assert physics[run]["samples"] == 11
        assert physics[run]["deviation_pos_max_m"] < 1e-3
    assert physics["closed_loop"]["completed"] is True
    gains = physics["servo_gains"]  # each joint's from its inertia, at 40 Hz
    omega = 2 * 3.141592653589793 * 40.0
    assert gains["omega_rad_s"] == {"leader": omega, "follower": omega}
    assert len(gains["kp_N_m_rad"]) == 12
    assert gains["kp_N_m_rad"][0] == pytest.approx(gains["inertia_kg_m2"][0] * omega ** 2)
    assert (short_run / "physics.png").is_file()
    assert summary["outputs"].count("physics.png") == 1
    report = (short_run / "report.html").read_text()
    assert 'id="physics"' in report and "physics.status: <b>ok</b>" in report
    assert main(["physics", str(short_run)]) == 0  # again: replaced, not added twice
    again = json.loads((short_run / "summary.json").read_text())
    assert again["outputs"].count("physics.png") == 1


def test_a_verdict_other_than_ok_exits_1_and_still_writes_everything(short_run, capsys):
    """A torque over its limit: exit code 1, the cause named, every output written."""
    resolved = short_run / "config.yaml"
    data = yaml.safe_load(resolved.read_text())
    data["physics"] = {"tau_max": {"leader": 1.0}}  # N m: far below what the beam needs
    resolved.write_text(yaml.safe_dump(data))
    assert main(["physics", str(short_run)]) == 1
    captured = capsys.readouterr()
    physics = json.loads((short_run / "summary.json").read_text())["physics"]
    assert physics["status"] == "torque" and physics["cause"] == "torque"
    assert physics["cause_sample"] == 0 and physics["cause_t_s"] == 0.0  # holding the load
    assert physics["message"].startswith("leader.joint")
    assert "passed its torque limit at t = 0.000 s (sample 0)" in physics["message"]
    assert "physics.status: torque (cause: torque, from t = 0.000 s, sample 0)" in captured.out
    assert f"physics check TORQUE: {physics['message']}" in captured.err
    assert (short_run / "physics.png").is_file()
    assert "physics.status: <b>torque</b>" in (short_run / "report.html").read_text()


@pytest.mark.slow
def test_a_servo_oscillation_is_named_and_fails_the_check(tmp_path, capsys):
    """One servo gain for every joint, too stiff and too little damped for the PUMA's
    wrists without armature: the closed loop oscillates at about 33 Hz, growing, until the
    controller stops it on the closure.
    The check exits 1 and names the oscillation, not a second-order error of the plan.
    (At kv = 300 the same file now ends `dropped`, the object spun off D(t): what an
    unstable wrist does is sensitive to the gains; kv = 100 gives the growing
    oscillation this test is about.)"""
    path = _short_beam(tmp_path, kp=5e4, kv=100, armature=0, rotation_max=170)  # deg: stopped
    data = yaml.safe_load(path.read_text())
    data["controller"]["duration"] = 0.62  # 20 samples; the loop stops before the last
    path.write_text(yaml.safe_dump(data))
    out = tmp_path / "run"
    assert main(["run", str(path), "--out", str(out), "--quiet", "--no-plots"]) == 0
    capsys.readouterr()
    assert main(["physics", str(out)]) == 1
    err = capsys.readouterr().err
    physics = json.loads((out / "summary.json").read_text())["physics"]
    assert physics["status"] == "stopped" and physics["cause"] == "oscillation"
    assert physics["cause_t_s"] < 0.1 and physics["closed_loop"]["samples"] < 21
    oscillation = physics["oscillation"]
    assert 25.0 < oscillation["frequency_hz"] < 40.0
    assert oscillation["largest_joint"].endswith(".joint6")  # a wrist
    assert "oscillated" in err and "then the controller stopped the closed loop" in err
    assert "second-order" not in err and "second-order" not in json.dumps(physics)
    # The same file run against the simulator: the measured closure fails first; the
    # plan, followed exactly, would have kept it, so the plan is not blamed.
    assert main(["run", str(path), "--out", str(tmp_path / "mj"), "--quiet", "--no-plots",
                 "--plant", "mujoco"]) == 1
    err = capsys.readouterr().err
    assert "grasp closure lost" in err and "the plant did not follow the command" in err
    assert "second-order" not in err


@pytest.mark.parametrize(("ratio", "words"), [(float("nan"), "no torque limits"),
                                               (None, "no torque limits"),
                                               (0.5, "torque/limit 0.5 ")])
def test_the_console_line_says_when_no_joint_has_a_torque_limit(ratio, words):
    from dualarm_qp.cli_commands import physics_line

    peaks = {"deviation_pos_max_m": 1e-4, "internal_force_max_N": 10.0,
             "follower_support_min_N": 15.0, "follower_support_max_N": 30.0,
             "slip_max_m": 1e-4, "torque_ratio_max": ratio, "wall_time_s": 2.0}
    line = physics_line("closed_loop", peaks)
    assert words in line and "nan" not in line


def test_a_failure_while_writing_leaves_the_folder_as_it_was(short_run, monkeypatch, capsys):
    before = {p.name: p.read_bytes() for p in short_run.iterdir()}

    def broken(path, data):
        raise OSError("disk full")

    monkeypatch.setattr("dualarm_qp.physics.command.write_json", broken)
    assert main(["physics", str(short_run)]) == 1
    assert "disk full" in capsys.readouterr().err
    after = {p.name: p.read_bytes() for p in short_run.iterdir()}
    assert after == before


@pytest.mark.slow
def test_a_failure_while_writing_again_keeps_the_earlier_figure(short_run, monkeypatch,
                                                                 capsys):
    assert main(["physics", str(short_run)]) == 0
    (short_run / "physics.png").write_bytes(b"an earlier check's figure")
    before = {p.name: p.read_bytes() for p in short_run.iterdir()}

    def broken(path, data):
        raise OSError("disk full")

    monkeypatch.setattr("dualarm_qp.physics.command.write_json", broken)
    assert main(["physics", str(short_run), "--delay"]) == 1
    assert "disk full" in capsys.readouterr().err
    assert {p.name: p.read_bytes() for p in short_run.iterdir()} == before


def test_not_a_run_folder_is_bad_input(tmp_path, capsys):
    assert main(["physics", str(tmp_path)]) == 2
    assert "summary.json" in capsys.readouterr().err


def test_a_bad_physics_section_of_the_run_is_bad_input(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["run", str(_short_beam(tmp_path, servo="position", kp=1000.0)),
                 "--out", str(out), "--quiet", "--no-plots"]) == 0
    resolved = out / "config.yaml"
    data = yaml.safe_load(resolved.read_text())
    data["physics"]["kv"] = -3
    resolved.write_text(yaml.safe_dump(data))
    assert main(["physics", str(out)]) == 2
    err = capsys.readouterr().err
    assert "physics.kv" in err and "config.yaml" in err


def test_a_torque_limit_of_the_wrong_length_is_bad_input_before_any_output(short_run,
                                                                         capsys):
    resolved = short_run / "config.yaml"
    data = yaml.safe_load(resolved.read_text())
    data["physics"] = {"tau_max": {"follower": [1, 2, 3]}}
    resolved.write_text(yaml.safe_dump(data))
    before = {p.name: p.read_bytes() for p in short_run.iterdir()}
    assert main(["physics", str(short_run)]) == 2
    err = capsys.readouterr().err
    assert "physics.tau_max.follower" in err and "config.yaml" in err
    assert "1 value" in err and "or 6" in err and "Traceback" not in err
    assert {p.name: p.read_bytes() for p in short_run.iterdir()} == before


def test_run_with_the_plant_refuses_a_torque_limit_of_the_wrong_length(tmp_path, capsys):
    path = _short_beam(tmp_path, tau_max={"leader": [10, 20]})
    out = tmp_path / "run"
    assert main(["run", str(path), "--out", str(out), "--quiet", "--no-plots",
                 "--plant", "mujoco"]) == 2
    err = capsys.readouterr().err
    assert "physics.tau_max.leader" in err and str(path) in err and "or 6" in err
    assert not out.exists()


UNSTABLE = {"kp": 1e11, "armature": 0}  # the servos blow the simulation up at once


def test_a_simulation_that_blows_up_fails_the_run_and_says_which_gain(tmp_path, capsys,
                                                                       monkeypatch):
    monkeypatch.chdir(tmp_path)  # MuJoCo appends its warning to MUJOCO_LOG.TXT here
    path = _short_beam(tmp_path, **UNSTABLE)
    out = tmp_path / "run"
    assert main(["run", str(path), "--out", str(out), "--quiet", "--no-plots",
                 "--plant", "mujoco"]) == 1
    err = capsys.readouterr().err
    assert "simulation diverged" in err and "unstable" in err and "lower physics.kp" in err
    assert "Traceback" not in err and not out.exists()


def test_a_physics_check_that_blows_up_fails_and_leaves_the_run(short_run, capsys,
                                                                 monkeypatch, tmp_path):
    monkeypatch.chdir(tmp_path)  # MuJoCo appends its warning to MUJOCO_LOG.TXT here
    resolved = short_run / "config.yaml"
    data = yaml.safe_load(resolved.read_text())
    data["physics"] = UNSTABLE
    resolved.write_text(yaml.safe_dump(data))
    before = {p.name: p.read_bytes() for p in short_run.iterdir()}
    assert main(["physics", str(short_run)]) == 1
    err = capsys.readouterr().err
    assert "simulation diverged" in err and "lower physics.kp" in err
    assert {p.name: p.read_bytes() for p in short_run.iterdir()} == before


@pytest.mark.slow
def test_the_delay_option_reaches_the_closed_loop(short_run):
    assert main(["physics", str(short_run), "--delay"]) == 0
    physics = json.loads((short_run / "summary.json").read_text())["physics"]
    assert physics["settings"]["delay_samples"] == 1
    assert main(["physics", str(short_run), "--delay", "3"]) == 0
    physics = json.loads((short_run / "summary.json").read_text())["physics"]
    assert physics["settings"]["delay_samples"] == 3


def test_a_delay_option_that_is_no_number_of_samples_exits_2(short_run, capsys):
    with pytest.raises(SystemExit) as stop:
        main(["physics", str(short_run), "--delay", "-2"])
    assert stop.value.code == 2
    assert "whole number of samples" in capsys.readouterr().err


@pytest.mark.slow
@pytest.mark.parametrize("config", [
    "puma_beam_limits.yaml",
    pytest.param("ur5_pair_sliding_bar.yaml", marks=pytest.mark.skipif(
        example_robots_dir() is None, reason="example-robot-data is not installed")),
])
def test_run_with_the_mujoco_plant_completes(tmp_path, config, capsys):
    out = tmp_path / "run"
    code = main(["run", str(CONFIGS / config), "--out", str(out), "--quiet", "--no-plots",
                 "--plant", "mujoco"])
    summary = json.loads((out / "summary.json").read_text())
    assert code == 0, summary["message"]
    assert summary["plant"] == "MujocoPlant" and summary["completed"]
    assert summary["projection"] is False
