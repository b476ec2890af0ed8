"""The ROS 2 cell on loopback: ``dualarm-qp drive --cell ros2`` against a stand-in.

The stand-in (``standin.py``) plays ros2_control on its own simulated clock, at a
quarter of real time (the machine may be busy); the node under test is the command
line, run in the ROS environment (``conftest.py``). Everything is asserted from the
drive's record (``trajectory.csv``, ``summary.json``) and the stand-in's log, on the
stand-in's clock, not on the wall clock.

The file is ``configs/fr3_pair.yaml`` (two 7-joint FR3 arms, joints named as a
ros2_control description names them), with the node on the stand-in's ``/clock``. The
stand-in runs in lockstep with the node (see ``standin.py``): each pair of commands lets
its clock run one sample, so the record's measured accelerations and jerks are those of
the commands, whatever the machine's load.
"""

from __future__ import annotations

import csv
import json
import signal
import subprocess
import time
from pathlib import Path

import numpy as np
import pytest
import yaml
from sigint import child_default_sigint

from dualarm_qp.experiments.config import load_config
from dualarm_qp.experiments.setup import build_experiment

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[2]
FR3 = ROOT / "configs" / "fr3_pair.yaml"
STAND_IN = Path(__file__).resolve().parent / "standin.py"
#: The stand-in's clock: 2 ms a tick, a tick every 8 ms of wall time when not in step.
PERIOD, WALL_PERIOD = 0.002, 0.008


def _config(folder: Path, **cell) -> Path:
    """fr3_pair on the stand-in's clock; in step with it, a state is never late: the
    watchdog is two samples."""
    raw = yaml.safe_load(FR3.read_text())
    raw["cell"].update(use_sim_time=True, watchdog=0.02)
    raw["cell"].update(cell)
    path = folder / "fr3_ros2.yaml"
    path.write_text(yaml.safe_dump(raw))
    return path


class StandIn:
    def __init__(self, ros_env, folder: Path, config: Path, **spec):
        cfg = load_config(config)
        exp = build_experiment(cfg, str(config))
        lead, foll = cfg.cell.leader, cfg.cell.follower
        self.leader, self.follower = list(lead.joints), list(foll.joints)
        self.task, self.dt = exp.task, exp.options.dt
        joints = dict(zip(self.leader, exp.initial.q_l.tolist(), strict=True))
        joints.update(zip(self.follower, exp.initial.q_f.tolist(), strict=True))
        self.log_path = folder / "standin.log"
        body = {"joints": joints, "controllers": {lead.controller: self.leader,
                                                  foll.controller: self.follower},
                "trajectory_controllers": {lead.trajectory_controller: self.leader,
                                           foll.trajectory_controller: self.follower},
                "interface": cfg.cell.interface, "period": PERIOD, "dt": exp.options.dt,
                "wall_period": WALL_PERIOD, "lockstep": True, "log": str(self.log_path),
                **spec}
        path = folder / "standin.json"
        path.write_text(json.dumps(body))
        self.proc = ros_env.popen([str(STAND_IN), str(path)], stdout=subprocess.PIPE,
                                  stderr=subprocess.PIPE, text=True)
        assert self.proc.stdout.readline().strip() == "ready", self.proc.stderr.read()

    def stop(self) -> list[dict]:
        if self.proc.poll() is None:
            self.proc.terminate()
            self.proc.communicate(timeout=30)
        return [json.loads(line) for line in self.log_path.read_text().splitlines()
                if line.endswith("}")]


def _drive(ros_env, config: Path, out: Path, *extra: str) -> subprocess.Popen:
    return ros_env.popen(["-m", "dualarm_qp", "drive", str(config), "--cell", "ros2", "--out",
                          str(out), "--no-plots", *extra], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True, preexec_fn=child_default_sigint)


def _record(out: Path) -> tuple[list[dict[str, str]], dict]:
    with (out / "trajectory.csv").open(newline="") as fh:
        rows = list(csv.DictReader(fh))
    return rows, json.loads((out / "summary.json").read_text())


def _commands(log: list[dict], controller: str) -> list[dict]:
    return [e for e in log if e.get("command") == controller]


def _assert_brought_to_rest(log, rows, summary, stand_in, cfg):
    """The last commands are zero, the joints stand still, the record ends at rest."""
    for controller in (cfg.cell.leader.controller, cfg.cell.follower.controller):
        cmds = _commands(log, controller)
        assert cmds, controller
        assert not np.any(cmds[-1]["data"])
    ticks = [e for e in log if "q" in e]
    last_cmd = max(e["t"] for e in log if "command" in e)
    still = [e["q"] for e in ticks if e["t"] > last_cmd]
    assert len(still) >= 2 and np.ptp(np.array(still), axis=0).max() == 0.0
    assert rows[-1]["status"] == "stopping"
    assert summary["cell"]["stop"]["at_rest"] is True
    sent = np.array([[float(r[k]) for k in r if "_sent" in k] for r in rows])
    assert not np.any(sent[-1])
    _assert_sent_within_limits(sent, stand_in)


def _assert_sent_within_limits(sent, stand_in):
    """Every command sent, from rest at the start to rest at the end, within the arms'
    speed and acceleration limits (the record's rates and their differences over dt)."""
    arms = (stand_in.task.leader, stand_in.task.follower)
    v_max = np.concatenate([a.qd_max for a in arms])
    a_max = np.concatenate([a.qdd_max for a in arms])
    assert sent.shape[1] == len(v_max)
    assert np.all(np.abs(sent) <= v_max * (1 + 1e-9))
    acc = np.abs(np.diff(np.vstack([np.zeros(len(v_max)), sent]), axis=0)) / stand_in.dt
    assert np.all(acc <= a_max * (1 + 1e-9)), float(np.max(acc / a_max))


@pytest.mark.parametrize("interface", ["velocity", "position"])
def test_the_node_drives_the_stand_in_through_the_whole_path(ros_env, tmp_path,
                                                             interface) -> None:
    config = _config(tmp_path, interface=interface)
    cfg = load_config(config)
    stand_in = StandIn(ros_env, tmp_path, config)
    try:
        drive = _drive(ros_env, config, tmp_path / "out")
        out, err = drive.communicate(timeout=600)
    finally:
        log = stand_in.stop()
    assert drive.returncode == 0, out + err
    rows, summary = _record(tmp_path / "out")
    assert summary["status"] == "completed"
    assert summary["path_completed_pct"] == pytest.approx(100.0)
    # the record is on the stand-in's clock: robot_t is its tick, one sample apart
    robot_t = np.array([float(r["robot_t"]) for r in rows])
    control = summary["cell"]["control_samples"]
    steps = np.diff(robot_t[:control])
    assert np.median(steps) == pytest.approx(0.01, abs=1e-9)
    ticks = {round(e["t"], 9) for e in log if "q" in e}
    assert {round(t, 9) for t in robot_t} <= ticks
    # each recorded joint is what the stand-in had at that tick (mapped by name)
    q_at = {round(e["t"], 9): e["q"] for e in log if "q" in e}
    n_l = len(stand_in.leader)
    for r, t in zip(rows[:control], robot_t[:control], strict=True):
        q = q_at[round(t, 9)]
        assert [float(r[f"ql{j + 1}"]) for j in range(n_l)] == pytest.approx(q[:n_l], abs=1e-12)
        assert [float(r[f"qf{j + 1}"]) for j in range(n_l)] == pytest.approx(q[n_l:], abs=1e-12)
    # what was sent reached the controllers, in the joints' order: the rates, or the
    # positions they reach at the next sample (from the measured start)
    sent_l = np.array([[float(r[f"ql_sent{j + 1}"]) for j in range(n_l)] for r in rows])
    heard = np.array([c["data"] for c in _commands(log, cfg.cell.leader.controller)])
    # every row's command goes out with it (the path's last row carries the stop's first),
    # the last too: the node waits for the controllers to have it before it closes
    assert len(heard) == len(rows)
    if interface == "velocity":
        np.testing.assert_array_equal(heard, sent_l)
        _assert_brought_to_rest(log, rows, summary, stand_in, cfg)
    else:
        q0 = np.array([float(rows[0][f"ql{j + 1}"]) for j in range(n_l)])
        np.testing.assert_allclose(heard, q0 + np.cumsum(sent_l, axis=0) * 0.01, atol=1e-12)
        np.testing.assert_array_equal(heard[-1], heard[-2])  # at rest: the position held
        assert not np.any(sent_l[-1])
        _assert_sent_within_limits(
            np.array([[float(r[k]) for k in r if "_sent" in k] for r in rows]), stand_in)
    # the grasp as a virtual joint and the step's status, published by the node
    grasps = [e for e in log if e.get("heard") == "grasp"]
    assert grasps and all(e["names"] == ["follower_grasp"] for e in grasps)
    recorded = {float(r["grasp"]) for r in rows}
    assert sum(e["position"][0] in recorded for e in grasps) >= 0.9 * len(rows)
    diags = [e for e in log if e.get("heard") == "diagnostics"]
    assert len(diags) >= 0.9 * len(rows)
    assert diags[-1]["message"] == "stopping" and diags[-1]["level"] == 1


def test_the_node_stops_when_the_joint_states_stop(ros_env, tmp_path) -> None:
    """The stand-in stops publishing joint states 1 s into the path (its clock goes on)."""
    config = _config(tmp_path)
    cfg = load_config(config)
    stand_in = StandIn(ros_env, tmp_path, config, freeze_after=1.0)
    try:
        drive = _drive(ros_env, config, tmp_path / "out")
        out, err = drive.communicate(timeout=600)
    finally:
        log = stand_in.stop()
    assert drive.returncode == 1, out + err
    assert "watchdog" in err
    rows, summary = _record(tmp_path / "out")
    assert summary["failure"]["criterion"] == "watchdog", summary["failure"]
    (freeze,) = [e["freeze_at"] for e in log if "freeze_at" in e]
    robot_t = np.array([float(r["robot_t"]) for r in rows])
    assert robot_t.max() < freeze  # no state after the freeze was acted on
    control = summary["cell"]["control_samples"]
    assert all(r["status"] != "stopping" for r in rows[:control])
    assert all(r["status"] == "stopping" for r in rows[control:])
    # it stopped within the watchdog's age after the last state, on the stand-in's clock
    stopped_at = float(rows[control - 1]["robot_t"]) + float(rows[control - 1]["state_age"])
    assert freeze <= stopped_at <= freeze + summary["cell"]["watchdog_s"] + 0.02
    assert len(rows) == summary["samples"]  # the record is whole
    _assert_brought_to_rest(log, rows, summary, stand_in, cfg)


@pytest.mark.sigint
@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_the_node_stops_safely_on_ctrl_c(ros_env, tmp_path, signum) -> None:
    config = _config(tmp_path)
    cfg = load_config(config)
    stand_in = StandIn(ros_env, tmp_path, config)
    try:
        drive = _drive(ros_env, config, tmp_path / "out")
        deadline = time.monotonic() + 300
        while len(_commands(stand_in_log(stand_in), cfg.cell.leader.controller)) < 60:
            assert drive.poll() is None, drive.communicate()
            assert time.monotonic() < deadline
            time.sleep(0.2)
        drive.send_signal(signum)
        out, err = drive.communicate(timeout=300)
    finally:
        log = stand_in.stop()
    assert drive.returncode == 130, out + err
    assert "Traceback" not in err
    rows, summary = _record(tmp_path / "out")
    assert summary["status"] == "interrupted"
    assert summary["cell"]["stop"]["reason"] == "interrupted"
    assert 0 < summary["path_completed_pct"] < 100
    _assert_brought_to_rest(log, rows, summary, stand_in, cfg)


def stand_in_log(stand_in: StandIn) -> list[dict]:
    return [json.loads(line) for line in stand_in.log_path.read_text().splitlines()
            if line.endswith("}")]


def test_a_verified_run_is_sent_whole_to_the_trajectory_controllers(ros_env, tmp_path) -> None:
    """One JointTrajectory per arm, one stamp for both; the arms end where the run ended.

    The stand-in runs by the wall clock here (no streamed commands to step with), at a
    quarter of real time, and the watch's watchdog is 0.2 s of its clock.
    """
    config = _config(tmp_path, watchdog=0.2)
    cfg = load_config(config)
    run = tmp_path / "run"
    done = subprocess.run([str(ros_env.python), "-m", "dualarm_qp", "run", str(config),
                           "--out", str(run), "--no-plots"], env=ros_env.env,
                          capture_output=True, text=True, timeout=600, check=False)
    assert done.returncode == 0, done.stdout + done.stderr
    stand_in = StandIn(ros_env, tmp_path, config, lockstep=False)
    try:
        drive = _drive(ros_env, config, tmp_path / "out", "--send-run", str(run))
        out, err = drive.communicate(timeout=600)
    finally:
        log = stand_in.stop()
    assert drive.returncode == 0, out + err
    sent = json.loads((tmp_path / "out" / "sent.json").read_text())
    assert sent["status"] == "completed" and sent["reason"] == "end"
    rows, _ = _record(run)
    trajs = [e for e in log if "trajectory" in e]
    assert [e["trajectory"] for e in trajs] == [cfg.cell.leader.trajectory_controller,
                                                cfg.cell.follower.trajectory_controller]
    assert trajs[0]["stamp"] == trajs[1]["stamp"] == pytest.approx(sent["start_s"], abs=1e-9)
    assert trajs[0]["stamp"] > trajs[0]["t"]  # a moment ahead, for both arms alike
    n_l = len(stand_in.leader)
    t0 = float(rows[0]["t"])
    for e, prefix, names in ((trajs[0], "ql", stand_in.leader),
                             (trajs[1], "qf", stand_in.follower)):
        assert e["names"] == names
        assert e["times"] == pytest.approx([float(r["t"]) - t0 for r in rows], abs=1e-9)
        assert e["positions"] == [[float(r[f"{prefix}{j + 1}"]) for j in range(len(names))]
                                  for r in rows]
    final = [e["q"] for e in log if "q" in e][-1]
    want = ([float(rows[-1][f"ql{j + 1}"]) for j in range(n_l)]
            + [float(rows[-1][f"qf{j + 1}"]) for j in range(n_l)])
    assert final == pytest.approx(want, abs=1e-12)
    assert sent["deviation_end_rad"] < 1e-9
