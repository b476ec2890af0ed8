"""``cell.headroom``: a cell's commands keep a share of every limit; the record is judged
against the whole limit."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from fake import KinematicCell

from dualarm_qp.cell.command import commanded
from dualarm_qp.cell.loop import DriveSettings, drive
from dualarm_qp.cell.safety import command_limits
from dualarm_qp.errors import ConfigError
from dualarm_qp.experiments.config import load_config, parse_config
from dualarm_qp.experiments.setup import build_experiment

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "configs" / "puma_beam_accel.yaml"


def test_commands_keep_the_headroom_and_the_record_is_judged_by_the_file() -> None:
    pytest.importorskip("franky_sim")  # the FR3's description
    config = ROOT / "configs" / "fr3_pair.yaml"
    exp = build_experiment(load_config(config), str(config))
    exp = dataclasses.replace(exp, duration=1.5)
    inner = commanded(exp, 0.4)
    for arm, full in ((inner.task.leader, exp.task.leader),
                      (inner.task.follower, exp.task.follower)):
        assert np.allclose(arm.qd_max, 0.6 * full.qd_max)
        assert np.allclose(arm.qdd_max, 0.6 * full.qdd_max)
        assert np.array_equal(arm.q_min, full.q_min)
    controller = inner.controller()
    cell = KinematicCell(exp.initial.q_l, exp.initial.q_f, exp.options.dt)
    res = drive(cell, controller, exp.initial, duration=exp.duration,
                settings=DriveSettings(watchdog=3 * exp.options.dt), limits=exp.limits,
                judged_by=exp.task)
    assert res.result.completed, res.result.message
    sent = np.array(cell.sends)
    full = command_limits(exp.controller())
    assert np.max(np.abs(sent) / full.v_max) <= 0.6 * (1 + 1e-9)
    v = np.vstack([np.zeros((2, full.n)), sent])
    assert np.max(np.abs(np.diff(v, axis=0)) / full.dt / full.a_max) <= 0.6 * (1 + 1e-9)
    assert np.max(np.abs(np.diff(v, n=2, axis=0)) / full.dt**2 / full.j_max) <= 0.6 * (1 + 1e-9)
    # the recorded motion is measured against the file's limits: 0.6 of them at most
    worst = max(r.speed_ratio for k, r in res.result.realised.items() if k != "grasp")
    assert 0.5 < worst <= 0.6 * (1 + 1e-6)


@pytest.mark.parametrize("value", [-0.1, 1.0])
def test_a_headroom_outside_0_1_is_refused(value: float) -> None:
    data = load_config(CONFIG).model_dump(mode="json", exclude_unset=True)
    data["cell"] = {"headroom": value}
    with pytest.raises(ConfigError, match=r"cell\.headroom.*must be in \[0, 1\)"):
        parse_config(data, "x.yaml")
