"""configs/sweeps/pillar_map.yaml: a sweep moves an obstacle of the scene.

An obstacle is an item of the list ``scene.obstacles``; a swept key addresses it by index
(``scene.obstacles.0.pose.position.0``) like any other list item, and the point's
experiment then holds the pillar where the point says, with the rest of the scene as in
the base file.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import yaml

from dualarm_qp.experiments import build_experiment
from dualarm_qp.experiments.config import parse_config
from dualarm_qp.sweep.labels import sweep_labels
from dualarm_qp.sweep.points import point_document
from dualarm_qp.sweep.spec import expand, load_sweep

ROOT = Path(__file__).resolve().parents[2]
SWEEP = ROOT / "configs" / "sweeps" / "pillar_map.yaml"
X, Y = "scene.obstacles.0.pose.position.0", "scene.obstacles.0.pose.position.1"


def test_the_pillar_map_moves_the_pillar_over_the_floor_plane():
    spec = load_sweep(SWEEP)
    assert spec.axes == [X, Y]
    points = expand(spec)
    xs = sorted({p.values[X] for p in points})
    ys = sorted({p.values[Y] for p in points})
    assert len(points) == len(xs) * len(ys) and min(xs) >= 500  # clear of the arms at t0
    assert 630 in range(min(xs), max(xs)) and 1100 in range(min(ys), max(ys) + 1)
    base = yaml.safe_load((SWEEP.parent / spec.base).read_text())
    for point in (points[0], points[len(points) // 2], points[-1]):
        doc = point_document(base, spec, point)
        exp = build_experiment(parse_config(doc, str(SWEEP)), str(SWEEP))
        scene = exp.task.scene
        assert scene is not None and scene.settings.enabled
        pillar = scene.obstacles[0].shape
        centre = (np.asarray(pillar.a) + np.asarray(pillar.b)) / 2
        np.testing.assert_allclose(centre, [point.values[X] / 1e3, point.values[Y] / 1e3, 0.0],
                                   atol=1e-12)
        assert pillar.radius == 0.05 and "object" in scene.body_names
    assert sweep_labels(spec.axes, {"length": "mm"}, spec.labels) == {
        X: "pillar x [mm]", Y: "pillar y [mm]"}


def test_a_pillar_through_an_arm_at_the_start_is_a_start_failure():
    from dualarm_qp.errors import ConfigError
    from dualarm_qp.sweep.points import is_start_failure
    from dualarm_qp.sweep.spec import Point

    spec = load_sweep(SWEEP)
    base = yaml.safe_load((SWEEP.parent / spec.base).read_text())
    point = Point(0, {X: 300, Y: 1380})  # the follower's shoulder
    doc = point_document(base, spec, point)
    try:
        build_experiment(parse_config(doc, str(SWEEP)), str(SWEEP))
    except ConfigError as err:
        assert err.key == "scene.obstacles.0.pose"
        assert is_start_failure(err)
    else:
        raise AssertionError("a pillar through the follower's shoulder was accepted")
    assert not is_start_failure(ConfigError("size must be positive",
                                            key="scene.obstacles.0.box"))
