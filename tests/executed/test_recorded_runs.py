"""Each (config variant, hard-limit solver) is run and its RECORDED trajectory is checked.

A completed run must keep every limit in trajectory.csv (speeds by finite differences,
ranges, path completed, leader tracking and grasp closure by the independent FK oracle);
a failed run must name a known criterion and leave a valid CSV. The verdict is read from
summary.json, but the limits are checked from the CSV only. Every hard-limit solver runs
the short variants and the baseline (FULL_MATRIX); the long ones run a representative
subset (SUBSET) to keep the suite near 90 s on two cores.

Set DUALARM_EXECUTED_LOG=FILE to append one JSON line per case (for reports).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
import yaml
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
from executed_runs import EXACT, HARD_SOLVERS, MUST_COMPLETE, VARIANTS, run

#: Variants run with every hard-limit solver (short runs, or the paper's baseline).
FULL_MATRIX = ("puma_beam_limits", "puma_beam_fast", "puma_beam_limits_x3",
               "puma_beam_limits_x3_accel",
               "puma_beam_fixed", "puma_beam_sliding_s7_100", "puma_beam_sliding_s7_1000",
               "puma_beam_tight_limits_scale", "puma_beam_wrist_singular")
#: The solvers run on the other (long) variants: both exact ones, SNS and the one
#: first-order QP backend (OSQP), which is the likeliest to graze a bound.
SUBSET = ("nullspace", "qp:daqp", "sns", "qp:osqp")

assert HARD_SOLVERS, "no hard-limit solver available"


def _log(record: dict) -> None:
    path = os.environ.get("DUALARM_EXECUTED_LOG")
    if path:
        with open(path, "a") as fh:
            fh.write(json.dumps(record) + "\n")


def _cases() -> list[tuple[str, str]]:
    """Every hard-limit solver on the short cases; a representative subset on the long ones."""
    cases = []
    for variant in VARIANTS:
        solvers = HARD_SOLVERS if variant in FULL_MATRIX else [
            s for s in HARD_SOLVERS if s in SUBSET]
        cases += [(variant, s) for s in solvers]
    return cases


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
    else:
        problems = check_valid(traj)
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
def test_cli_exit_code_matches_summary(variant: str, tmp_path: Path) -> None:
    """The CLI's exit code is 0 for a completed run, 1 for a failed one, as summary says."""
    cfg = tmp_path / f"{variant}.yaml"
    cfg.write_text(yaml.safe_dump(VARIANTS[variant]()))
    out = tmp_path / "out"
    exe = Path(sys.executable).with_name("dualarm-qp")
    proc = subprocess.run([str(exe), "run", str(cfg), "--solver", "nullspace", "--out",
                           str(out), "--no-plots", "--quiet"], capture_output=True, text=True,
                          timeout=120)
    summary = json.loads((out / "summary.json").read_text())
    assert proc.returncode == (0 if summary["completed"] else 1), (proc.returncode,
                                                                   proc.stderr)
    traj = read_trajectory(out / "trajectory.csv")
    assert not check_valid(traj)
