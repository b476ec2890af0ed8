"""The command line: outputs, exit codes and messages."""

from __future__ import annotations

import csv
import json
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from dualarm_qp.cli import main
from dualarm_qp.experiments.outputs import atomic_open

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
PAPER = CONFIGS / "puma_beam_sliding_s7_100.yaml"

REQUIRED_COLUMNS = [
    "t", *(f"ql{i}" for i in range(1, 7)), *(f"qf{i}" for i in range(1, 7)), "grasp", "m",
    "closure_pos_err", "closure_rot_err", "solve_time_s", "status",
]


def short_config(tmp_path: Path, **controller) -> Path:
    d = yaml.safe_load(PAPER.read_text())
    d["controller"]["duration"] = 0.31  # 10 steps
    d["controller"].update(controller)
    path = tmp_path / "short.yaml"
    path.write_text(yaml.safe_dump(d))
    return path


@pytest.mark.slow
def test_run_writes_outputs(tmp_path, capsys):
    out = tmp_path / "out"
    code = main(["run", str(short_config(tmp_path)), "--out", str(out), "--quiet"])
    assert code == 0
    for name in ("summary.json", "trajectory.csv", "joints.png", "rates.png", "grasp.png",
                 "tracking.png", "closure.png", "report.html"):
        assert (out / name).is_file(), name
    with (out / "trajectory.csv").open() as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 11
    assert all(c in rows[0] for c in REQUIRED_COLUMNS)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["completed"] is True
    assert summary["samples"] == 11
    assert summary["closure_pos_err_max_m"] < 1e-6
    assert "completed" in capsys.readouterr().out


@pytest.mark.parametrize("enabled", [False, True])
def test_run_with_a_collision_scene_prints_the_clearance(tmp_path, capsys, enabled):
    d = yaml.safe_load((CONFIGS / "puma_beam_limits.yaml").read_text())
    d["controller"]["duration"] = 0.31
    d["object"]["shape"] = {"box": {"size": [40, 40, 500]}, "pose": {"position": [0, 0, 250]}}
    d["collision"] = {"enabled": enabled}
    config = tmp_path / "scene.yaml"
    config.write_text(yaml.safe_dump(d))
    out = tmp_path / "out"
    assert main(["run", str(config), "--out", str(out), "--quiet", "--no-plots"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    r = summary["realised_limits"]["clearance"]
    lines = [ln for ln in capsys.readouterr().out.splitlines() if "clearance" in ln]
    assert len(lines) == 1
    assert f"smallest {r['min_m'] * 1e3:.1f} mm ({r['pair']}, sample {r['sample']})" in lines[0]
    if enabled:
        assert lines[0].endswith("safety distance 20 mm kept (allowance 1 mm)")
    else:
        assert lines[0].endswith("measured only (collision avoidance off)")


@pytest.mark.parametrize("solver", ["nullspace", "qp:daqp", "fixed_grasp"])
def test_run_with_solver_override(tmp_path, solver):
    out = tmp_path / "o"
    config = short_config(tmp_path, velocity_limits=True, grasp_speed_max=100)
    assert main(["run", str(config), "--solver", solver, "--out", str(out),
                 "--quiet", "--no-plots"]) == 0
    assert json.loads((out / "summary.json").read_text())["solver"] == solver


@pytest.mark.parametrize("solver", ["nullspace", "qp:daqp"])
def test_unlimited_first_jump_fails_a_hard_limit_run_on_the_closure(tmp_path, solver, capsys):
    """Without speed limits Table 2's grasp jumps back into range in one sample.

    The linearised step then opens the closure far beyond 1 mm; a hard-limit solver may
    not hide that behind an unbounded position-level correction, so the run fails and
    says so (exit 1, criterion "closure").
    """
    out = tmp_path / "o"
    assert main(["run", str(short_config(tmp_path)), "--solver", solver, "--out", str(out),
                 "--quiet", "--no-plots"]) == 1
    summary = json.loads((out / "summary.json").read_text())
    assert summary["completed"] is False
    assert summary["failure"]["criterion"] == "closure"
    assert summary["failure"]["sample"] == 1
    assert "grasp closure lost" in capsys.readouterr().err


def test_unknown_key_exit_2_one_clear_line(tmp_path, capsys):
    d = yaml.safe_load(PAPER.read_text())
    d["controller"]["gian"] = 1
    path = tmp_path / "typo.yaml"
    path.write_text(yaml.safe_dump(d))
    assert main(["run", str(path), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    assert str(path) in err and "controller.gian" in err and "correction_gain" in err
    assert len(err.strip().splitlines()) == 1
    assert not (tmp_path / "o").exists()


def test_missing_file_and_unknown_solver_exit_2(tmp_path, capsys):
    assert main(["run", str(tmp_path / "missing.yaml")]) == 2
    assert "file not found" in capsys.readouterr().err
    assert main(["run", str(short_config(tmp_path)), "--solver", "qp:nope"]) == 2
    err = capsys.readouterr().err
    assert "unknown solver 'qp:nope'" in err and "nullspace" in err


def test_uninstalled_backend_names_the_pip_extra(tmp_path, capsys):
    from dualarm_qp.solvers import list_solvers

    missing = [s for s in list_solvers() if not s.available and s.extra]
    if not missing:
        pytest.skip("every registered backend is installed here")
    assert main(["run", str(short_config(tmp_path)), "--solver", missing[0].name]) == 2
    assert f"dualarm-qp[{missing[0].extra}]" in capsys.readouterr().err


def test_failed_run_exit_1_and_partial_outputs(tmp_path, capsys):
    # Joint speed limits far too low for the object speed, and policy "stop":
    # the first infeasible step stops the run; what completed is still written.
    d = yaml.safe_load(short_config(tmp_path).read_text())
    d["controller"].update(velocity_limits=True, policy="stop")
    d["solver"] = {"name": "nullspace"}
    d["follower"]["qd_max"] = [0.01] * 6
    path = tmp_path / "slow.yaml"
    path.write_text(yaml.safe_dump(d))
    out = tmp_path / "o"
    assert main(["run", str(path), "--out", str(out), "--quiet", "--no-plots"]) == 1
    err = capsys.readouterr().err
    assert "conflicting bounds" in err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["completed"] is False
    assert "conflicting bounds" in summary["message"]
    assert (out / "trajectory.csv").is_file()


def test_solvers_lists_everything(capsys):
    assert main(["solvers"]) == 0
    out = capsys.readouterr().out
    for name in ("reference", "fixed_grasp", "nullspace", "sns", "qp:osqp", "qp:proxsuite",
                 "qp:daqp"):
        assert name in out


def test_no_command_prints_help_exit_2(capsys):
    assert main([]) == 2
    assert "usage" in capsys.readouterr().out


def test_atomic_write_keeps_old_file_on_failure(tmp_path):
    target = tmp_path / "f.txt"
    target.write_text("old")
    with pytest.raises(RuntimeError), atomic_open(target) as fh:
        fh.write("half")
        raise RuntimeError("boom")
    assert target.read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["f.txt"]


@pytest.mark.slow
@pytest.mark.parametrize("module", ["dualarm_qp.cli", "dualarm_qp"])
def test_console_script_entry_point(tmp_path, module):
    proc = subprocess.run([sys.executable, "-m", module, "--version"],
                          capture_output=True, text=True, check=False)
    assert proc.returncode == 0 and "dualarm-qp" in proc.stdout


@pytest.mark.slow
def test_reproduce_shows_the_papers_claims(tmp_path, capsys):
    assert main(["reproduce", "--out", str(tmp_path), "--quiet"]) == 0
    rep = json.loads((tmp_path / "reproduce.json").read_text())
    claims = rep["checks"]["claims"]
    assert claims["case_a_leaves_joint3_range"]
    assert claims["case_b_joint3_inside"] and claims["case_c_joint3_inside"]
    for fig in ("fig5_joint3.png", "fig6_grasp.png"):
        assert (tmp_path / fig).stat().st_size > 1000
    for case in ("a", "b", "c"):
        assert rep["cases"][case]["closure_pos_err_max_m"] < 1e-6
        assert rep["cases"][case]["closure_rot_err_max_rad"] < 1e-6
    # one page leads to each case: its report and its animation, both there
    page = (tmp_path / "report.html").read_text()
    assert "report.html" in rep["outputs"] and "open " in capsys.readouterr().out
    for case in "abcd":
        for name in ("report.html", "animation.html"):
            assert f'href="case_{case}/{name}"' in page
            assert (tmp_path / f"case_{case}" / name).is_file()
    assert page.count('src="data:image/png;base64,') == 2  # Figs. 5 and 6


def test_unwritable_output_folder_is_bad_input(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    for argv in (["run", str(short_config(tmp_path)), "--out", str(blocker / "sub")],
                 ["reproduce", "--out", str(blocker)]):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert "cannot write the output folder" in err and "Traceback" not in err


def test_unknown_solver_in_the_file_names_file_and_key(tmp_path, capsys):
    d = yaml.safe_load(short_config(tmp_path).read_text())
    d["solver"]["name"] = "qp:bogus"
    path = tmp_path / "bogus.yaml"
    path.write_text(yaml.safe_dump(d))
    assert main(["run", str(path)]) == 2
    err = capsys.readouterr().err
    assert str(path) in err and "solver.name" in err and "nullspace" in err


def test_solvers_table_has_a_header_and_install_hints(capsys):
    from dualarm_qp.solvers import list_solvers

    assert main(["solvers"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].split()[:3] == ["SOLVER", "INSTALLED", "BOUNDS"]
    assert lines[1].startswith("reference ")
    for s in list_solvers():
        if not s.available and s.extra:
            assert any(f"dualarm-qp[{s.extra}]" in line for line in lines)


def test_solver_options_pass_through_and_bad_ones_are_named(tmp_path, capsys):
    from dualarm_qp.experiments import build_experiment, load_config

    d = yaml.safe_load(short_config(tmp_path).read_text())
    d["solver"] = {"name": "qp:osqp", "options": {"eps_abs": 1e-9, "max_iter": 123}}
    good = tmp_path / "good.yaml"
    good.write_text(yaml.safe_dump(d))
    solver = build_experiment(load_config(good)).controller().solver
    assert solver.options["eps_abs"] == 1e-9 and solver.options["max_iter"] == 123
    d["solver"]["options"] = {"eps_absolute": 1e-9}
    bad = tmp_path / "bad.yaml"
    bad.write_text(yaml.safe_dump(d))
    assert main(["run", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "solver.options" in err and "eps_absolute" in err
