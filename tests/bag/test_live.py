"""The live view: a Foxglove WebSocket server on 127.0.0.1 serving the bag's stream.

A WebSocket client written for the tests (``ws_client.py``) connects, reads what the
server advertises, subscribes and receives the messages, which are compared with the
bag's (a replayed run) or with the drive's record (a live drive).
"""

from __future__ import annotations

import dataclasses
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_typestore
from sigint import child_default_sigint
from ws_client import FoxgloveClient

from dualarm_qp.bag.live import LiveView, open_drive_view, replay
from dualarm_qp.bag.messages import TOPICS
from dualarm_qp.bag.write import RunStream, write_bag
from dualarm_qp.cell.loop import DriveSettings, drive
from dualarm_qp.experiments.config import load_config
from dualarm_qp.experiments.setup import build_experiment

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "cell"))
from fake import KinematicCell

ROOT = Path(__file__).resolve().parents[2]
ACCEL = ROOT / "configs" / "puma_beam_accel.yaml"
STORE = get_typestore(Stores.ROS2_JAZZY)


def _subscribe_all(client: FoxgloveClient, view: LiveView | None = None):
    channels = client.advertised(len(TOPICS))
    assert set(channels) == set(TOPICS)
    for topic, ch in channels.items():
        assert ch["encoding"] == "cdr"
        assert ch["schemaName"] == TOPICS[topic]
        assert ch["schemaEncoding"] == "ros2msg"
    client.send_json({"op": "subscribe", "subscriptions": [
        {"id": i, "channelId": int(ch["id"])} for i, ch in enumerate(channels.values())]})
    by_sub = {i: topic for i, topic in enumerate(channels)}
    if view is not None:  # the server takes the subscription in its own time
        deadline = time.monotonic() + 20
        while not all(view.subscribed(t) for t in TOPICS):
            assert time.monotonic() < deadline, "the subscription never reached the server"
            time.sleep(0.01)
    return by_sub


def _bag_raw(path: Path) -> list[tuple[str, int, bytes]]:
    with AnyReader([path], default_typestore=STORE) as reader:
        return [(c.topic, t, bytes(raw)) for c, t, raw in reader.messages()]


def test_a_replayed_run_serves_the_bags_messages(run_dir, tmp_path) -> None:
    bag, _ = write_bag(run_dir, tmp_path / "bag")
    want = _bag_raw(bag)
    stream = RunStream.read(run_dir)
    view = LiveView(stream.messages.store, port=0)
    client = FoxgloveClient(view.port)
    try:
        assert client.protocol == "foxglove.sdk.v1"
        by_sub = _subscribe_all(client, view)
        thread = threading.Thread(target=replay, args=(view, list(stream.stream())),
                                  kwargs={"rate": 50.0, "loops": 1}, daemon=True)
        thread.start()
        got = client.messages(len(want))
        thread.join(timeout=30)
    finally:
        client.close()
        view.close()
    served = [(by_sub[sub], t, data) for sub, t, data in got]
    # message for message, the bag's bytes (per topic in order; topics interleave)
    for topic in TOPICS:
        assert [m for m in served if m[0] == topic] == [m for m in want if m[0] == topic]


def test_the_replay_keeps_the_runs_pace() -> None:
    class Sink:
        def __init__(self):
            self.times = []

        def publish(self, msg):
            self.times.append(time.monotonic())

    from dualarm_qp.bag.messages import Message

    msgs = [Message("/tf", k * 50_000_000, b"") for k in range(5)]  # every 50 ms
    sink = Sink()
    start = time.monotonic()
    assert replay(sink, msgs, rate=2.0, loops=2) == 10
    # 25 ms apart at twice the pace: never sooner (a busy machine may be later)
    assert sink.times[4] - start >= 4 * 0.025
    assert sink.times[9] - sink.times[5] >= 4 * 0.025


def test_a_drive_is_served_live_as_it_is_recorded() -> None:
    cfg = load_config(ACCEL)
    exp = dataclasses.replace(build_experiment(cfg, str(ACCEL)), duration=0.3)
    view = open_drive_view(cfg, exp, str(ACCEL), port=0)
    client = FoxgloveClient(view.view.port)
    try:
        by_sub = _subscribe_all(client, view.view)
        cell = KinematicCell(exp.initial.q_l, exp.initial.q_f, exp.options.dt)
        res = drive(cell, exp.controller(), exp.initial, duration=exp.duration,
                    settings=DriveSettings(watchdog=3 * exp.options.dt), limits=exp.limits,
                    observer=view)
        trace = res.result.trace
        got = client.messages(3 * len(trace))
    finally:
        client.close()
        view.view.close()
    assert res.result.completed, res.result.message
    assert res.cell["stop"]["samples"] > 0  # a stop ran: its rows are served as recorded
    states = [STORE.deserialize_cdr(data, TOPICS["/joint_states"])
              for sub, _, data in got if by_sub[sub] == "/joint_states"]
    assert len(states) == len(trace)
    for k, js in enumerate(states):
        assert js.position.tolist() == [*trace.q_l[k], *trace.q_f[k], trace.grasp[k]]
        assert js.velocity.tolist() == [*trace.ql_dot[k], *trace.qf_dot[k], trace.m[k]]
    diags = [STORE.deserialize_cdr(data, TOPICS["/diagnostics"])
             for sub, _, data in got if by_sub[sub] == "/diagnostics"]
    assert [d.status[0].message for d in diags] == list(trace.status)  # stop rows too


def test_a_port_in_use_is_bad_input(capsys) -> None:
    view = LiveView(STORE, port=0)
    try:
        from dualarm_qp.errors import InvalidInputError

        with pytest.raises(InvalidInputError, match=str(view.port)):
            LiveView(STORE, port=view.port)
    finally:
        view.close()


@pytest.mark.slow
@pytest.mark.sigint
def test_bag_foxglove_serves_until_ctrl_c(run_dir) -> None:
    proc = subprocess.Popen(
        [sys.executable, "-m", "dualarm_qp", "bag", str(run_dir), "--foxglove", "--port", "0",
         "--rate", "5"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        preexec_fn=child_default_sigint, env=dict(os.environ, PYTHONUNBUFFERED="1"))
    try:
        line = proc.stdout.readline()
        assert "ws://127.0.0.1:" in line, line + proc.stderr.read()
        port = int(line.split("ws://127.0.0.1:")[1].split()[0])
        client = FoxgloveClient(port)
        by_sub = _subscribe_all(client)
        got = client.messages(30)  # it replays again and again: these come
        client.close()
        assert {by_sub[s] for s, _, _ in got} >= {"/joint_states", "/tf", "/diagnostics"}
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 130, err
    assert "Traceback" not in err


def test_an_interrupt_inside_the_observer_leaves_the_record_whole() -> None:
    """Ctrl-C while a sample is being published: the loop stops as on any interrupt, the
    record is whole and the observer never sees a row that was not recorded."""
    cfg = load_config(ACCEL)
    exp = dataclasses.replace(build_experiment(cfg, str(ACCEL)), duration=0.6)
    seen: list[tuple[int, str, float]] = []

    def observer(trace, k):
        seen.append((k, trace.status[k], float(trace.t[k])))
        if k == 5 and len(seen) == 6:
            raise KeyboardInterrupt("Ctrl-C while publishing")

    cell = KinematicCell(exp.initial.q_l, exp.initial.q_f, exp.options.dt)
    res = drive(cell, exp.controller(), exp.initial, duration=exp.duration,
                settings=DriveSettings(watchdog=3 * exp.options.dt), limits=exp.limits,
                observer=observer)
    assert res.result.failure.criterion == "interrupted"
    trace = res.result.trace
    assert all(len(v) == len(trace) for v in res.columns.values())
    assert [k for k, _, _ in seen] == list(range(len(trace)))
    assert all(status for _, status, _ in seen)
    assert [t for _, _, t in seen] == trace.t.tolist()
    assert trace.status[6:] == ["stopping"] * (len(trace) - 6)
