"""Every solver that takes rows keeps the clearance; the others refuse collision avoidance.

Each available solver with ``takes_rows`` (the registry) runs the beam task with a ball in
the follower's way, collision avoidance on (executed_runs.SCENE_VARIANTS): it completes,
or stops with criterion ``collision`` naming a pair of the scene, and its RECORDED motion
never comes closer than d_s - allowance (recomputed from trajectory.csv by
clearance_check, not read from summary.json). The set-up where the ball blocks the task
must stop with ``collision``, never break through. SNS, ``reference`` and ``fixed_grasp``
take no rows: the command line refuses a file with collision avoidance on (exit 2).
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import yaml
from clearance_check import check_clearance, recompute
from csv_check import check_completed_run, check_valid, read_trajectory
from executed_runs import ROW_SOLVERS, SCENE_VARIANTS, run

from dualarm_qp.cli import main
from dualarm_qp.solvers import available_solvers
from dualarm_qp.solvers.registry import solver_info

#: The solver whose runs stay in the fast loop (the others: 1-3 s each with the check).
FAST = ("nullspace",)
#: Solvers that take no rows (available ones).
NO_ROWS = [n for n in available_solvers() if not solver_info(n).takes_rows]

assert ROW_SOLVERS, "no solver takes rows"


def _cases() -> list:
    return [pytest.param(s, marks=() if s in FAST else pytest.mark.slow) for s in ROW_SOLVERS]


def _named_pair(message: str, pairs: list[str]) -> str | None:
    return next((p for p in pairs if p in message), None)


@pytest.mark.parametrize("solver", _cases())
def test_every_row_solver_keeps_the_clearance(solver: str, tmp_path: Path) -> None:
    exp, summary = run("puma_beam_ball", solver, tmp_path)
    traj = read_trajectory(tmp_path / "trajectory.csv")
    pairs = exp.task.scene.pair_names
    if summary["completed"]:
        problems = check_completed_run(traj, exp)   # every limit, the clearance included
    else:
        failure = summary["failure"]
        assert failure["criterion"] == "collision", failure
        assert _named_pair(failure["message"], pairs), failure["message"]
        problems = check_valid(traj) or check_clearance(traj, exp)
    assert not problems, "\n".join(problems)
    # The rows were needed: the nearest pair came within 1 mm of d_s.
    d_s = exp.task.scene.settings.safety_distance
    assert recompute(traj, exp).distance.min() < d_s + 1e-3


@pytest.mark.parametrize("solver", _cases())
def test_a_blocked_task_stops_without_breaking_the_clearance(solver: str,
                                                             tmp_path: Path) -> None:
    exp, summary = run("puma_beam_ball_blocked", solver, tmp_path)
    traj = read_trajectory(tmp_path / "trajectory.csv")
    assert not summary["completed"]
    failure = summary["failure"]
    assert failure["criterion"] == "collision", failure
    assert _named_pair(failure["message"], exp.task.scene.pair_names) == "follower.link2 - ball"
    problems = check_valid(traj) or check_clearance(traj, exp)
    assert not problems, "\n".join(problems)


@pytest.mark.parametrize("solver", NO_ROWS)
def test_solvers_without_rows_refuse_collision_avoidance(solver: str, tmp_path: Path,
                                                         capsys: pytest.CaptureFixture[str]
                                                         ) -> None:
    config = tmp_path / "ball.yaml"
    config.write_text(yaml.safe_dump(SCENE_VARIANTS["puma_beam_ball"]()))
    out = tmp_path / "out"
    code = main(["run", str(config), "--solver", solver, "--out", str(out), "--no-plots",
                 "--quiet"])
    err = capsys.readouterr().err
    assert code == 2, err
    assert f"solver '{solver}'" in err and "'collision' gives rows" in err
    assert "nullspace" in err                      # it names the solvers that can
    assert not (out / "summary.json").exists()
    # The same file with collision avoidance off runs with that solver.
    data = SCENE_VARIANTS["puma_beam_ball_off"]()
    data["controller"]["duration"] = 0.31
    config.write_text(yaml.safe_dump(data))
    assert main(["run", str(config), "--solver", solver, "--out", str(out), "--no-plots",
                 "--quiet"]) in (0, 1)
    assert json.loads((out / "summary.json").read_text())["collision"]["enabled"] is False


def test_sns_reference_and_fixed_grasp_take_no_rows() -> None:
    """The registry says so (what the refusal above reads)."""
    for name in ("sns", "reference", "fixed_grasp"):
        assert not solver_info(name).takes_rows
    assert set(NO_ROWS) >= {"sns", "reference", "fixed_grasp"}
