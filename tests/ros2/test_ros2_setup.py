"""The ROS 2 cell without ROS: its settings, the joint-state mapping, what it refuses.

The project's own environment has no rclpy; these run there (the loopback tests run the
node in the ROS environment: ``test_ros2_loopback.py``).
"""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import numpy as np
import pytest
import yaml

from dualarm_qp.cell.base import CellSetupError
from dualarm_qp.cell.ros2 import ArmTopics, JointStates, ros2_settings
from dualarm_qp.cli import main
from dualarm_qp.experiments.config import load_config
from dualarm_qp.experiments.setup import build_experiment

ROOT = Path(__file__).resolve().parents[2]
FR3 = ROOT / "configs" / "fr3_pair.yaml"
NO_RCLPY = importlib.util.find_spec("rclpy") is None


def _arms():
    return (ArmTopics("leader", ("a1", "a2"), "/joint_states", "/l/commands", None),
            ArmTopics("follower", ("b1", "b2", "b3"), "/joint_states", "/f/commands", None))


def test_joint_states_are_mapped_by_name_whatever_their_order() -> None:
    js = JointStates(_arms())
    assert js.missing() == ["a1", "a2", "b1", "b2", "b3"]
    js.update(["b3", "other", "a2", "b1", "a1", "b2"], [5.0, 9.0, 2.0, 3.0, 1.0, 4.0], 0.5)
    assert js.missing() == []
    r = js.reading()
    assert r.t == 0.5
    assert r.q_l.tolist() == [1.0, 2.0]
    assert r.q_f.tolist() == [3.0, 4.0, 5.0]


def test_a_reading_is_as_old_as_its_oldest_joint() -> None:
    """Per-arm topics: one arm's state that stops coming ages the whole reading."""
    js = JointStates(_arms())
    js.update(["a1", "a2"], [1.0, 2.0], 1.0)
    js.update(["b1", "b2", "b3"], [3.0, 4.0, 5.0], 1.0)
    js.update(["a1", "a2"], [1.5, 2.5], 1.2)  # the follower's broadcaster went quiet
    r = js.reading()
    assert r.t == 1.0
    assert r.q_l.tolist() == [1.5, 2.5]


def test_the_reading_at_a_sample_instant_is_the_last_one_stamped_no_later() -> None:
    js = JointStates(_arms())
    names = ["a1", "a2", "b1", "b2", "b3"]
    for k in range(10):
        js.update(names, [float(k)] * 5, 0.002 * k)
    assert js.reading(0.010).q_l.tolist() == [5.0, 5.0]
    assert js.reading(0.0109).t == pytest.approx(0.010)
    assert js.reading(None).t == pytest.approx(0.018)
    assert js.reading(-1.0).t == 0.0  # nothing that old: the oldest kept
    for k in range(10, 10 + JointStates.HISTORY):
        js.update(names, [float(k)] * 5, 0.002 * k)
    assert js.reading(0.0).t == pytest.approx(0.002 * 10)  # the history is bounded
    assert math.isfinite(js.newest_t)


def test_the_settings_come_from_the_files_cell_section() -> None:
    cfg = load_config(FR3)
    exp = build_experiment(cfg, str(FR3))
    s = ros2_settings(cfg, exp, str(FR3))
    assert s.interface == "velocity" and s.use_sim_time is False and s.dt == 0.01
    leader, follower = s.arms
    assert leader.joints == tuple(cfg.cell.leader.joints)
    assert leader.command_topic == "/leader_velocity_controller/commands"
    assert follower.trajectory_topic == "/follower_trajectory_controller/joint_trajectory"
    assert np.isclose(exp.options.dt, s.dt)


@pytest.mark.parametrize(("edit", "message"), [
    (lambda c: c["leader"].pop("joints"), "cell.leader.joints"),
    (lambda c: c["follower"].update(joints=c["follower"]["joints"][:6]), "got 6"),
    (lambda c: c["follower"].pop("controller"), "cell.follower.controller"),
])
def test_a_cell_section_the_node_cannot_use_is_refused(tmp_path, edit, message) -> None:
    raw = yaml.safe_load(FR3.read_text())
    edit(raw["cell"])
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(raw))
    cfg = load_config(path)
    with pytest.raises(CellSetupError, match=message):
        ros2_settings(cfg, build_experiment(cfg, str(path)), str(path))


def test_a_dry_run_needs_no_controller(tmp_path) -> None:
    raw = yaml.safe_load(FR3.read_text())
    raw["cell"]["leader"].pop("controller")
    path = tmp_path / "dry.yaml"
    path.write_text(yaml.safe_dump(raw))
    cfg = load_config(path)
    s = ros2_settings(cfg, build_experiment(cfg, str(path)), str(path), need="")
    assert s.arms[0].command_topic is None


@pytest.mark.skipif(not NO_RCLPY, reason="rclpy is installed here")
def test_without_rclpy_the_drive_says_how_to_get_it(tmp_path, capsys) -> None:
    code = main(["drive", str(FR3), "--cell", "ros2", "--out", str(tmp_path / "out")])
    assert code == 2
    err = capsys.readouterr().err
    assert "rclpy" in err and "setup.bash" in err
    assert not (tmp_path / "out").exists()


def test_a_run_to_send_is_the_runs_motion_and_a_rollout_is_the_same(tmp_path) -> None:
    import dataclasses

    from dualarm_qp.cell.ros2_trajectory import plan_from_rollout, plan_from_run
    from dualarm_qp.experiments.run import run_experiment

    exp = build_experiment(load_config(FR3), str(FR3))
    exp = dataclasses.replace(exp, duration=0.2)
    outcome = run_experiment(exp, tmp_path, progress=False, plots=False)
    assert outcome.ok
    a, b = plan_from_run(tmp_path, exp), plan_from_rollout(exp)
    assert a.t[0] == 0.0 and len(a.t) == len(outcome.result.trace)
    np.testing.assert_array_equal(a.q_l, outcome.result.trace.q_l)
    np.testing.assert_array_equal(a.ql_dot[:-1], outcome.result.trace.ql_dot[:-1])
    assert not np.any(a.ql_dot[-1]) and not np.any(a.qf_dot[-1])  # at rest at the end
    np.testing.assert_allclose(a.q_f, b.q_f, atol=1e-12)
    q_l, _ = a.at(a.t[3] / 2 + a.t[4] / 2)
    np.testing.assert_allclose(q_l, (a.q_l[3] + a.q_l[4]) / 2, atol=1e-15)


@pytest.mark.parametrize("what", ["failed_run", "other_cell", "dry_run"])
def test_what_send_run_refuses(tmp_path, capsys, what) -> None:
    args = ["drive", str(FR3), "--cell", "ros2", "--out", str(tmp_path / "out"), "--send-run"]
    if what == "failed_run":
        run = tmp_path / "run"
        run.mkdir()
        (run / "summary.json").write_text('{"status": "failed"}')
        args.append(str(run))
    elif what == "other_cell":
        args[3] = "mujoco"
    else:
        args.append("--dry-run")
    assert main(args) == 2
    err = capsys.readouterr().err
    assert {"failed_run": "did not complete", "other_cell": "--cell ros2",
            "dry_run": "no dry run"}[what] in err


def test_every_test_process_takes_the_same_lock_to_build_the_ros_environment() -> None:
    """Two test workers must wait for each other, not build ``.venv-ros`` together."""
    import runpy
    import subprocess
    import sys

    conftest = str(ROOT / "tests" / "ros2" / "conftest.py")
    here = runpy.run_path(conftest)["lock_path"]()
    probe = f"import runpy; print(runpy.run_path({conftest!r})['lock_path']())"
    there = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                           check=True).stdout.strip()
    assert there == str(here) and there.endswith(".lock")


def test_two_test_processes_never_share_a_ros_domain() -> None:
    """A domain is held by one test process at a time (a lock per domain)."""
    import runpy

    ros_domain = runpy.run_path(str(ROOT / "tests" / "ros2" / "conftest.py"))["ros_domain"]
    for _ in range(20):
        with ros_domain() as a, ros_domain() as b:
            assert a != b and 1 <= min(a, b) and max(a, b) <= 101


def test_the_docs_install_the_wheels_the_tests_run_on() -> None:
    """docs/ros2.md's environment of community wheels is the one the tests build."""
    import re
    import runpy

    packages = runpy.run_path(str(ROOT / "tests" / "ros2" / "conftest.py"))["ROS_PACKAGES"]
    section = (ROOT / "docs" / "ros2.md").read_text().split("the community wheels\n")[1]
    (block,) = re.findall(r"```bash\n(.*?)```", section.split("\n## ")[0], re.DOTALL)
    assert sorted(re.findall(r"\bros-jazzy-[a-z0-9-]+", block)) == sorted(packages)
    assert "zz_dualarm_qp_project.pth" in block and "site.addsitedir" in block
