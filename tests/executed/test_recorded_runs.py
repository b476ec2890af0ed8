"""Each (config variant, hard-limit solver) is run and its RECORDED trajectory is checked.

A completed run must keep every limit in trajectory.csv (speeds by finite differences,
ranges, path completed, leader tracking and grasp closure by the independent FK oracle);
a failed run must name a known criterion and leave a valid CSV. The verdict is read from
summary.json, but the limits are checked from the CSV only; a run with a collision scene
also keeps its recorded clearance (recomputed from the CSV's joints: clearance_check.py),
and only solvers that take rows run a variant with collision avoidance on. Every
hard-limit solver runs
the short variants and the baseline (FULL_MATRIX); the long ones run a representative
subset (SUBSET). The fast loop (``-m "not slow"``) keeps the cases ``_fast`` selects.

Set DUALARM_EXECUTED_LOG=FILE to append one JSON line per case (for reports).
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import pytest
import yaml
from clearance_check import check_clearance
from csv_check import (
    FAILURE_CRITERIA,
    check_completed_run,
    check_geometry,
    check_ranges,
    check_speeds,
    check_valid,
    limits_of,
    read_trajectory,
    worst_shares,
)
from executed_runs import (
    EXACT,
    HARD_SOLVERS,
    MUST_COMPLETE,
    ROW_SOLVERS,
    VARIANTS,
    collision_enabled,
    run,
)

from dualarm_qp.cli import main

#: Variants run with every hard-limit solver (short runs, or the paper's baseline).
FULL_MATRIX = ("puma_beam_limits", "puma_beam_fast", "puma_beam_limits_x3",
               "puma_beam_limits_x3_accel",
               "puma_beam_fixed", "puma_beam_sliding_s7_100", "puma_beam_sliding_s7_1000",
               "puma_beam_tight_limits_scale", "puma_beam_wrist_singular")
#: The solvers run on the other (long) variants: both exact ones, SNS and the one
#: first-order QP backend (OSQP), which is the likeliest to graze a bound.
SUBSET = ("nullspace", "qp:daqp", "sns", "qp:osqp")
#: Variants every hard-limit solver runs in the fast loop (a fraction of a second each).
QUICK = ("puma_beam_fixed", "puma_beam_sliding_s7_100", "puma_beam_sliding_s7_1000",
         "puma_beam_fast")


def _fast(variant: str, solver: str) -> bool:
    """In the fast loop: every solver on QUICK, the exact ones on the baseline, each
    policy with ``nullspace``; the other cases take 1-5 s each and are marked slow."""
    return (variant in QUICK or (variant == "puma_beam_limits" and solver in EXACT)
            or (variant.startswith("puma_beam_tight_limits_") and solver == "nullspace")
            or (variant == "puma_beam_ball_off" and solver == "nullspace"))

assert HARD_SOLVERS, "no hard-limit solver available"


def _log(record: dict) -> None:
    path = os.environ.get("DUALARM_EXECUTED_LOG")
    if path:
        with open(path, "a") as fh:
            fh.write(json.dumps(record) + "\n")


def _cases() -> list[Any]:
    """Every hard-limit solver on the short cases; a representative subset on the long ones."""
    cases = []
    for variant in VARIANTS:
        solvers = HARD_SOLVERS if variant in FULL_MATRIX else [
            s for s in HARD_SOLVERS if s in SUBSET]
        if collision_enabled(VARIANTS[variant]()):  # the others refuse (exit 2)
            solvers = [s for s in solvers if s in ROW_SOLVERS]
        cases += [pytest.param(variant, s, marks=() if _fast(variant, s) else pytest.mark.slow)
                  for s in solvers]
    return cases


@pytest.mark.slow
@pytest.mark.parametrize(("variant", "solver"), _cases())
def test_recorded_run_keeps_limits(variant: str, solver: str, tmp_path: Path) -> None:
    exp, summary = run(variant, solver, tmp_path)
    traj = read_trajectory(tmp_path / "trajectory.csv")
    completed = summary.get("completed")
    assert completed in (True, False), summary
    refused = (summary.get("failure") or {}).get("criterion") == "unreachable"
    if completed:
        problems = check_completed_run(traj, exp)
    elif refused:  # refused before its first sample: a header and no row
        problems = [] if len(traj["t"]) == 0 else ["rows in a run refused before its start"]
    else:  # a failed run's partial record is valid and keeps its clearance too
        problems = check_valid(traj) or check_clearance(traj, exp)
    failure = summary.get("failure") or {}
    record = {"variant": variant, "solver": solver, "policy": str(exp.policy),
              "completed": completed, "criterion": failure.get("criterion"),
              "failure": failure or None, "rows": len(traj["t"]), "problems": problems}
    if not refused and not check_valid(traj):
        record["worst"] = worst_shares(traj, exp)
    if not completed and not refused and not check_valid(traj):
        # Not asserted: does the partial record of a failed run keep the limits too?
        lim = limits_of(exp)
        record["partial_problems"] = (check_speeds(traj, lim) + check_ranges(traj, lim)
                                      + check_geometry(traj, exp))
    _log(record)

    if completed:
        assert not problems, ("summary.json says completed, but the recorded trajectory "
                              "breaks rules:\n" + "\n".join(problems))
    else:
        assert failure.get("criterion") in FAILURE_CRITERIA, summary
        assert not problems, "failed run left an invalid CSV:\n" + "\n".join(problems)
    if solver in EXACT and variant in MUST_COMPLETE:
        assert completed, f"{solver} must complete {variant}; failure: {failure}"


@pytest.mark.parametrize("variant", ["puma_beam_fast", "puma_beam_fixed"])
def test_cli_exit_code_matches_summary(variant: str, tmp_path: Path,
                                       capsys: pytest.CaptureFixture[str]) -> None:
    """The CLI's exit code is 0 for a completed run, 1 for a failed one, as summary says
    (``main``'s return value is the process's exit code: ``sys.exit(main())``)."""
    cfg = tmp_path / f"{variant}.yaml"
    cfg.write_text(yaml.safe_dump(VARIANTS[variant]()))
    out = tmp_path / "out"
    code = main(["run", str(cfg), "--solver", "nullspace", "--out", str(out), "--no-plots",
                 "--quiet"])
    summary = json.loads((out / "summary.json").read_text())
    assert code == (0 if summary["completed"] else 1), (code, capsys.readouterr().err)
    traj = read_trajectory(out / "trajectory.csv")
    assert not check_valid(traj)
