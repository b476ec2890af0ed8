"""The embedded cluster starts while the driver checks the points, and is always closed.

A stand-in for the cluster records when it was started and whether it was closed; the
sweep stops before it would be used (the tests of test_sweep_run.py run real clusters).
"""

from __future__ import annotations

import json

import pytest
from sweep_tools import write_sweep

from dualarm_qp.bench.runner import code_digest
from dualarm_qp.errors import ConfigError
from dualarm_qp.sweep import points as points_module
from dualarm_qp.sweep import runner as runner_module
from dualarm_qp.sweep.points import prepare_points
from dualarm_qp.sweep.runner import SweepSettings, run_sweep
from dualarm_qp.sweep.spec import load_sweep


@pytest.fixture
def clusters(monkeypatch):
    """Every StartingCluster made, as ``(points checked when started, closed)``."""
    checks: list[object] = []
    made: list[dict] = []
    real_check = points_module.check_point

    def counting(*args, **kwargs):
        checks.append(args)
        return real_check(*args, **kwargs)

    class Starting:
        def __init__(self, workers=None):
            self.record = {"checked": len(checks), "closed": 0, "workers": workers}
            made.append(self.record)

        def close(self):
            self.record["closed"] += 1

    monkeypatch.setattr(points_module, "check_point", counting)
    monkeypatch.setattr(runner_module, "StartingCluster", Starting)
    monkeypatch.setattr(runner_module, "_drive", lambda drv, *a: drv)  # stop before running
    return made


def test_the_cluster_starts_before_the_first_point_is_checked(tmp_path, clusters):
    drv = run_sweep(load_sweep(write_sweep(tmp_path)), tmp_path / "out",
                    settings=SweepSettings(workers=2))
    assert clusters == [{"checked": 0, "closed": 1, "workers": 2}]  # not taken: closed
    assert drv.started is not None


def test_no_cluster_for_an_external_scheduler(tmp_path, clusters):
    run_sweep(load_sweep(write_sweep(tmp_path)), tmp_path / "out",
              settings=SweepSettings(scheduler="tcp://127.0.0.1:1"))
    assert clusters == []


def test_no_cluster_when_every_point_is_stored(tmp_path, clusters):
    spec = load_sweep(write_sweep(tmp_path))
    out = tmp_path / "out"
    out.mkdir()
    keys = [t.key for t in prepare_points(spec, code_digest())]
    (out / "points.jsonl").write_text("".join(json.dumps({"key": k}) + "\n" for k in keys))
    run_sweep(spec, out)
    assert clusters == []
    lines = (out / "points.jsonl").read_text().splitlines()
    (out / "points.jsonl").write_text("\n".join(lines[1:]) + "\n")  # one point short
    run_sweep(spec, out)
    assert len(clusters) == 1 and clusters[0]["closed"] == 1


def test_bad_input_closes_the_cluster_started_for_it(tmp_path, clusters):
    bad = write_sweep(tmp_path, "bad", grid={"controller.dt": [0.031, -1.0]})
    with pytest.raises(ConfigError, match=r"controller\.dt"):
        run_sweep(load_sweep(bad), tmp_path / "out")
    assert clusters == [{"checked": 0, "closed": 1, "workers": None}]
    assert not (tmp_path / "out").exists()  # nothing written before the checks passed
