"""The live view serves the page on 127.0.0.1, streams updates and stops cleanly."""

from __future__ import annotations

import socket
import threading
import urllib.request

import numpy as np
import pytest

from dualarm_qp.errors import InvalidInputError
from dualarm_qp.step.state import DualArmState
from dualarm_qp.viz import LiveView


def _view_threads():
    return [t for t in threading.enumerate() if t.name == "dualarm-live-view"]


def test_live_view_serves_streams_and_closes(beam):
    state = DualArmState(t=0.0, q_l=beam.initial.q_l, q_f=beam.initial.q_f,
                         sigma=beam.initial.sigma)
    with LiveView(beam.task, open_browser=False) as view:
        assert view.url.startswith("http://127.0.0.1:")
        page = urllib.request.urlopen(view.url, timeout=10).read().decode()
        assert 'id="dualarm-data"' in page and "connect-src 'self'" in page
        view.update(state, status="optimal", scale=1.0)
        stream = urllib.request.urlopen(view.url + "events", timeout=10)
        first = stream.readline().decode()
        assert first.startswith("data: {") and '"nodes"' in first
        view.update(q_l=beam.initial.q_l, q_f=beam.initial.q_f, grasp=0.2, t=0.1)
        stream.readline()  # the blank line ending the first event
        assert '"t":[0.1]' in stream.readline().decode()
        port = int(view.url.rsplit(":", 1)[1].strip("/"))
        assert view.samples == 2
    assert view.closed and not _view_threads()
    rest = stream.read().decode()  # the stream ends once the view closes
    assert "event: close" in rest
    with pytest.raises(OSError), socket.create_connection(("127.0.0.1", port), timeout=2):
        pass
    with pytest.raises(InvalidInputError, match="closed"):
        view.update(state)


def test_update_needs_joints_of_the_right_size(beam):
    view = LiveView(beam.task, open_browser=False)
    try:
        with pytest.raises(InvalidInputError):
            view.update(q_l=beam.initial.q_l[:3], q_f=beam.initial.q_f, grasp=0.1)
        with pytest.raises(InvalidInputError, match="grasp"):
            view.update(q_l=beam.initial.q_l, q_f=beam.initial.q_f)
    finally:
        view.close()
    view.close()  # a second close does nothing
    assert not _view_threads()


def test_a_live_view_of_a_collision_scene_streams_the_nearest_pair(pillar):
    """The pillar's task: each update carries the nearest pair within d_i, as a run's page."""
    import json

    scene = pillar.task.scene
    with LiveView(pillar.task, open_browser=False) as view:
        page = urllib.request.urlopen(view.url, timeout=10).read().decode()
        assert '"obstacles":[{"name":"pillar"' in page
        view.update(q_l=pillar.initial.q_l, q_f=pillar.initial.q_f, grasp=pillar.initial.sigma)
        stream = urllib.request.urlopen(view.url + "events", timeout=10)
        event = json.loads(stream.readline().decode().removeprefix("data: "))
    (pair,), (distance,), (points,) = event["near_pair"], event["near_distance"], event["near"]
    assert scene.pair_names[pair] == "follower.link1 - pillar"
    assert 0.0 < distance < scene.settings.influence_distance
    assert np.linalg.norm(np.subtract(points[3:], points[:3])) == pytest.approx(distance)
