"""What a rollout reports while it runs (the share of the path, the time lost) and the
task scale it records, on the sample where the path ends and on the last one too."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from dualarm_qp.control.rollout import rollout
from dualarm_qp.experiments import build_experiment, load_config
from dualarm_qp.experiments.setup import Experiment

CONFIG = Path(__file__).resolve().parents[2] / "configs" / "puma_beam_sliding_s7_100.yaml"


def beam(tmp_path: Path, *, slow: bool, duration: float = 0.62) -> Experiment:
    """The paper's beam (case b) with hard limits; ``slow``: follower joints too slow for it.

    At 1.2 and 3 deg/s the follower cannot keep up with the object's 32 mm/s: the
    ``scale`` policy slows the path, and the run needs about 1.8 times the duration.
    """
    d = yaml.safe_load(CONFIG.read_text())
    d["solver"] = {"name": "nullspace"}
    d["controller"].update(duration=duration, duration_cap=4 * duration,
                           velocity_limits=True, grasp_speed_max=50)
    if slow:
        d["follower"]["qd_max"] = [1.2, 1.2, 1.2, 3.0, 3.0, 3.0]  # deg/s
    path = tmp_path / "beam.yaml"
    path.write_text(yaml.safe_dump(d))
    return build_experiment(load_config(path), str(path))


def run(exp: Experiment, progress=None):  # type: ignore[no-untyped-def]
    return rollout(exp.controller(), exp.initial, duration=exp.duration, limits=exp.limits,
                   project=exp.project, progress=progress)


def test_progress_counts_the_path_not_the_samples(tmp_path: Path) -> None:
    exp = beam(tmp_path, slow=True)
    calls: list[tuple[float, float]] = []
    res = run(exp, lambda done, lost: calls.append((done, lost)))
    tr = res.trace
    assert res.completed, res.message
    nominal = round(exp.duration / exp.options.dt) + 1
    assert len(calls) == len(tr) > nominal + 10  # slowed: many more samples than nominal
    done = np.array([c[0] for c in calls])
    lost = np.array([c[1] for c in calls])
    np.testing.assert_allclose(done, (tr.tau - tr.tau[0]) / exp.duration, rtol=0, atol=1e-12)
    assert done[0] == 0.0 and done[-1] == 1.0  # the whole path, however long it took
    assert np.all(np.diff(done) > 0)
    assert np.all(np.diff(lost) >= 0)
    assert lost[-1] == pytest.approx(res.time_lost) and res.time_lost > 0.5


def test_progress_of_a_run_that_lost_no_time(tmp_path: Path) -> None:
    calls: list[tuple[float, float]] = []
    res = run(beam(tmp_path, slow=False), lambda done, lost: calls.append((done, lost)))
    assert res.completed, res.message
    assert calls[-1] == (1.0, 0.0) and all(lost == 0.0 for _, lost in calls)


def test_the_task_scale_is_recorded_without_the_path_end_artefacts(tmp_path: Path) -> None:
    """The last row's command (no motion: the path is done) is never applied, and the
    sample before it is shortened to land on the path's end: neither is a slowing."""
    exp = beam(tmp_path, slow=True)
    tr = run(exp).trace
    dt, end = exp.options.dt, tr.tau[0] + exp.duration
    assert end - tr.tau[-2] < 0.5 * dt  # the path ended early in the last applied sample
    # The task scale is the share of the rate asked for: full speed, or what is left.
    advanced = np.diff(tr.tau)
    asked = np.minimum(dt, end - tr.tau[:-1])
    np.testing.assert_allclose(advanced, tr.scale[:-1] * asked, rtol=1e-9, atol=1e-15)
    status = np.array(tr.status)
    assert np.array_equal(tr.scale < 1.0, status == "scaled")  # slowed when it says so
    assert tr.scale[-2] == 1.0 and status[-2] != "scaled"  # the shortened sample
    assert tr.scale[-1] == tr.scale[-2]  # the last row: the scale the path ended at
    assert np.any(tr.scale < 0.95)


def test_a_run_that_lost_no_time_records_scale_1_to_its_end(tmp_path: Path) -> None:
    res = run(beam(tmp_path, slow=False))
    assert res.time_lost == 0.0
    assert res.trace.status[-1] != "scaled"
    assert np.all(res.trace.scale == 1.0)  # the last row too (was 0 where the path ends)
