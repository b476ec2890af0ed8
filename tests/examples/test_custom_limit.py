"""The example's wall, a limit written by a user, holds in the recorded motion.

The follower's tool position is recomputed from the recorded joints with the
independent DH oracle (plain numpy, no Pinocchio) for every solver that keeps rows; the
same run without the wall crosses it, so the check can fail.
"""

from __future__ import annotations

import runpy
import sys
from pathlib import Path

import numpy as np
import pytest

import dualarm_qp as dq
from dualarm_qp.errors import PairingError
from dualarm_qp.solvers import list_solvers

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from dh_oracle import fk

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "configs" / "puma_beam_limits.yaml"
EXAMPLE = runpy.run_path(str(ROOT / "examples" / "custom_limit.py"))
Wall = EXAMPLE["Wall"]

ROW_SOLVERS = [i.name for i in list_solvers() if i.available and i.takes_rows
               and i.hard_bounds]
FAST = ("nullspace", "qp:daqp")


def wall_and_experiment(solver: str, with_wall: bool = True):
    probe = dq.build_experiment(dq.load_config(CONFIG), str(CONFIG))
    start = probe.task.follower.fk(probe.initial.q_f)[:3, 3]
    wall = Wall(normal=[0.0, -1.0, 0.0], offset=-(start[1] - 0.150))
    exp = dq.build_experiment(dq.load_config(CONFIG), str(CONFIG), solver=solver,
                              limits=[wall] if with_wall else [])
    return wall, exp


def oracle_heights(exp, q_f: np.ndarray, wall) -> np.ndarray:
    f = exp.task.follower
    rows = np.column_stack([f.dh.a, f.dh.alpha, f.dh.d, f.dh.offset])
    return np.array([wall.normal @ fk(rows, q, "standard", base=f.base, tool=f.tool)[:3, 3]
                     for q in q_f])


def check(solver: str) -> None:
    wall, exp = wall_and_experiment(solver)
    res = dq.rollout(exp.controller(), exp.initial, duration=exp.duration, limits=exp.limits)
    assert res.completed, res.message
    heights = oracle_heights(exp, res.trace.q_f, wall)
    assert heights.max() <= wall.offset, (solver, heights.max() - wall.offset)
    assert heights.max() >= wall.offset - 2 * wall.margin  # it binds: the tool reached it


@pytest.mark.parametrize("solver", [s for s in FAST if s in ROW_SOLVERS])
def test_the_wall_holds_in_the_recorded_motion(solver: str) -> None:
    check(solver)


@pytest.mark.slow
@pytest.mark.parametrize("solver", [s for s in ROW_SOLVERS if s not in FAST])
def test_the_wall_holds_for_every_solver_that_takes_rows(solver: str) -> None:
    check(solver)


def test_without_the_wall_the_tool_crosses_it() -> None:
    wall, exp = wall_and_experiment("nullspace", with_wall=False)
    res = dq.rollout(exp.controller(), exp.initial, duration=exp.duration, limits=exp.limits)
    assert oracle_heights(exp, res.trace.q_f, wall).max() > wall.offset + 0.05


def test_a_solver_that_takes_boxes_only_is_refused_before_anything_runs() -> None:
    with pytest.raises(PairingError) as info:
        wall_and_experiment("sns")
    err = info.value
    assert err.solver == "sns" and err.limits == ("wall",)
    assert "nullspace" in err.able and "sns" not in err.able
