"""The example's task, a weighted task written by a user, holds in the recorded motion.

The run writes ``trajectory.csv``; the check reads the follower's elbow (column ``qf3``)
and the summary back from the files, independently of the controller that ran: the
elbow stays within a degree of its start, the run completes (the object on D(t), the
grasp closed, every hard limit kept in the recorded motion), and the same run without
the task turns the elbow by more than 20 degrees, so the check can fail.
"""

from __future__ import annotations

import csv
import json
import runpy
from pathlib import Path

import numpy as np
import pytest

import dualarm_qp as dq
from dualarm_qp.errors import PairingError

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "configs" / "puma_beam_limits.yaml"
EXAMPLE = runpy.run_path(str(ROOT / "examples" / "custom_task.py"))
HoldJoint = EXAMPLE["HoldJoint"]


def _recorded(out: Path) -> tuple[np.ndarray, dict]:
    with (out / "trajectory.csv").open() as fh:
        elbow = np.array([float(row["qf3"]) for row in csv.DictReader(fh)])
    return elbow, json.loads((out / "summary.json").read_text())


def _run(tmp_path: Path, with_task: bool, solver: str = "nullspace"):
    probe = dq.build_experiment(dq.load_config(CONFIG), str(CONFIG))
    q_star = float(probe.initial.q_f[2])
    tasks = [HoldJoint(2, q_star)] if with_task else []
    exp = dq.build_experiment(dq.load_config(CONFIG), str(CONFIG), solver=solver, tasks=tasks)
    out = tmp_path / f"{solver.replace(':', '_')}_{with_task}"
    dq.run_experiment(exp, out, plots=False)
    return (q_star, *_recorded(out))


@pytest.mark.parametrize("solver", ["nullspace", "qp:daqp"])
def test_the_elbow_is_held_in_the_recorded_motion(tmp_path, solver):
    q_star, elbow, summary = _run(tmp_path, True, solver)
    assert summary["completed"], summary.get("failure")
    assert np.degrees(np.abs(elbow - q_star).max()) < 1.0


def test_without_the_task_the_elbow_turns(tmp_path):
    q_star, elbow, summary = _run(tmp_path, False)
    assert summary["completed"]
    assert np.degrees(np.abs(elbow - q_star).max()) > 20.0


def test_a_solver_that_takes_a_diagonal_cost_only_is_refused():
    probe = dq.build_experiment(dq.load_config(CONFIG), str(CONFIG))
    with pytest.raises(PairingError, match="diagonal cost"):
        dq.build_experiment(dq.load_config(CONFIG), str(CONFIG), solver="sns",
                            tasks=[HoldJoint(2, float(probe.initial.q_f[2]))])
