"""configs/puma_beam_pillar.yaml, run three ways, checked from the recorded motion.

The file's story: with collision avoidance the sliding grasp carries the beam to the end
of the path and keeps the safety distance from the pillar; without it, the sliding grasp
and the fixed grasp (Zheng-Luh) both drive the follower's upper arm into the pillar. The
file runs through ``dualarm-qp collisions`` (the three runs in one command), and every
pair's distance is recomputed from each ``trajectory.csv`` with the tests' own
kinematics and distances (:mod:`clearance_check`), not the library's.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from clearance_check import check_clearance, penetrations, recompute
from csv_check import read_trajectory

from dualarm_qp.cli import main
from dualarm_qp.experiments.config import load_config
from dualarm_qp.experiments.setup import build_experiment

PILLAR = Path(__file__).resolve().parents[2] / "configs" / "puma_beam_pillar.yaml"
UPPER_ARM = "follower.link2 - pillar"


@pytest.mark.slow
def test_the_sliding_grasp_avoids_the_pillar_and_the_others_run_into_it(tmp_path):
    out = tmp_path / "cmp"
    assert main(["collisions", str(PILLAR), "--out", str(out), "--quiet", "--no-plots",
                 "--expect-penetration"]) == 0  # the demo's story, claimed
    record = json.loads((out / "collisions.json").read_text())
    assert record["claims"] == {"avoiding_completes_and_keeps_clearance": True,
                                "not_avoiding_penetrates": True,
                                "fixed_grasp_penetrates": True}
    upper_arm, grasp = {}, {}
    for label in ("avoiding", "not_avoiding", "fixed_grasp"):
        # Each run's config.yaml is the file as that run ran it (avoidance on or off).
        exp = build_experiment(load_config(out / label / "config.yaml"), str(PILLAR))
        assert exp.task.scene.settings.enabled is (label == "avoiding")
        traj = read_trajectory(out / label / "trajectory.csv")
        # The CSV's clearance columns are the recomputed ones; with avoidance on, every
        # pair stays at or above d_s less the allowance.
        assert check_clearance(traj, exp) == [], label
        rec = recompute(traj, exp)
        upper_arm[label] = rec.distance[:, rec.pairs.index(UPPER_ARM)]
        grasp[label] = traj["grasp"]
        overlaps = penetrations(rec)
        if label == "avoiding":
            assert overlaps == []
        else:  # the upper arm enters the pillar (the fixed grasp's elbow too), nothing else
            entered = {o.split(":")[0].removeprefix("penetration ") for o in overlaps}
            assert UPPER_ARM in entered <= {UPPER_ARM, "follower.link3 - pillar"}, entered
        assert traj["path_t"][-1] == pytest.approx(15.5)  # the whole path, every run
    assert upper_arm["avoiding"].min() >= 0.020 - 0.001
    assert grasp["avoiding"][-1] < 0.2  # slid towards the leader to make room
    # Without avoidance the sliding grasp hardly slides; the fixed grasp holds 450 mm and
    # its upper arm goes deeper into the pillar.
    assert upper_arm["not_avoiding"].min() < -0.005 and grasp["not_avoiding"][-1] > 0.35
    assert upper_arm["fixed_grasp"].min() < upper_arm["not_avoiding"].min()
    np.testing.assert_allclose(grasp["fixed_grasp"], 0.45)
