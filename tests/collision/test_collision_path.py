"""The path check before a run, and the report of a recorded clearance."""

from __future__ import annotations

import numpy as np

from dualarm_qp.collision import CollisionScene, CollisionSettings
from dualarm_qp.collision.clearance import ClearanceHistory, clearance_report
from dualarm_qp.collision.path import path_collision
from dualarm_qp.geometry import Box, Capsule
from dualarm_qp.kinematics import puma560
from dualarm_qp.poses import pose
from dualarm_qp.task.trajectory import LinearTrajectory


def _scene(obstacle):
    leader, follower = puma560(), puma560().with_base(pose([0.3, 1.38, 0.0]))
    bar = Box([0.04, 0.04, 0.7], pose([0, 0, 0.35]))
    return CollisionScene.build(leader, follower, settings=CollisionSettings(),
                                object_shape=bar, obstacles=[("post", obstacle)])


def _path():
    # The object moves along +x at 0.1 m/s for 10 s from x = 0.
    return LinearTrajectory([0.0, 0.0, 0.0], [0.1, 0.0, 0.0], t0=0.0, tf=10.0)


def test_the_path_into_a_post_is_found_where_it_first_comes_within_d_s():
    # A post standing on the x axis at x = 0.5, radius 0.05: the bar (its cross-section
    # 0.04 wide, centred on the path) comes within d_s = 0.02 when x >= 0.5 - 0.05 - 0.02
    # - 0.02, at t = 4.1 s.
    post = Capsule([0.5, 0.0, -1.0], [0.5, 0.0, 1.0], 0.05)
    hit = path_collision(_scene(post), _path(), 0.0, 10.0, 0.01)
    assert hit is not None
    assert hit.obstacle == "post"
    assert abs(hit.t - 4.1) <= 0.011
    assert hit.distance < 0.02
    assert "post" in hit.message and "t = " in hit.message


def test_a_post_beside_the_path_is_no_collision():
    post = Capsule([0.5, 0.3, -1.0], [0.5, 0.3, 1.0], 0.05)
    assert path_collision(_scene(post), _path(), 0.0, 10.0, 0.01) is None


def test_the_report_names_the_first_breach_and_the_minimum():
    scene = _scene(Capsule([5, 5, 0], [5, 5, 1], 0.1))
    d = np.array([0.05, 0.03, 0.0195, 0.01, 0.04])
    hist = ClearanceHistory(np.tile(d[:, None], (1, 4)), d, ["a - b"] * 5)
    rep = clearance_report(scene, hist)
    assert rep.minimum == 0.01 and rep.sample == 3
    assert rep.breach_sample == 3  # 0.0195 is below d_s but within the 1 mm allowance
    assert not rep.kept
    hist2 = ClearanceHistory(np.tile(d[:3, None], (1, 4)), d[:3], ["a - b"] * 3)
    assert clearance_report(scene, hist2).kept
