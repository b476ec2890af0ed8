"""Solver options: the file's belong to its solver; --solver-option names its solver."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import yaml

from dualarm_qp.cli import main
from dualarm_qp.errors import ConfigError, InvalidInputError
from dualarm_qp.experiments import build_experiment, load_config, parse_config
from dualarm_qp.experiments.options import (
    SolverFlagError,
    check_solver_options,
    options_for,
    parse_solver_options,
)
from dualarm_qp.solvers import available_solvers, get_solver
from dualarm_qp.solvers.qp import backend_options
from dualarm_qp.solvers.registry import SolverOptionError

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
PAPER = CONFIGS / "puma_beam_sliding_s7_100.yaml"


def config_with_options(tmp_path: Path, solver: str = "qp:osqp",
                        options: dict | None = None) -> Path:
    d = yaml.safe_load(PAPER.read_text())
    d["controller"].update(duration=0.124, velocity_limits=True, grasp_speed_max=100)
    d["solver"] = {"name": solver, "options": options or {"eps_abs": 1e-9, "max_iter": 123}}
    path = tmp_path / "opts.yaml"
    path.write_text(yaml.safe_dump(d))
    return path


def test_file_options_apply_only_to_the_files_solver(tmp_path):
    path = config_with_options(tmp_path)
    cfg = load_config(path)
    own = build_experiment(cfg, str(path))
    assert own.solver_options == {"eps_abs": 1e-9, "max_iter": 123}
    assert own.controller().solver.options["max_iter"] == 123
    other = build_experiment(cfg, str(path), solver="nullspace")
    assert other.solver_options == {}
    other.controller()  # nullspace built without osqp's options
    alias = build_experiment(cfg, str(path), solver="qp:osqp")
    assert alias.solver_options == own.solver_options


def test_a_config_with_options_runs_with_another_solver(tmp_path):
    path = config_with_options(tmp_path)
    out = tmp_path / "o"
    assert main(["run", str(path), "--solver", "nullspace", "--out", str(out), "--quiet",
                 "--no-plots"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["solver"] == "nullspace"


def test_bad_file_options_are_refused_even_with_another_solver(tmp_path, capsys):
    path = config_with_options(tmp_path, options={"eps_absolute": 1e-9})
    assert main(["run", str(path), "--solver", "nullspace", "--out",
                 str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "solver.options.eps_absolute" in err and "eps_abs" in err
    assert not (tmp_path / "o").exists()


def test_bench_compares_a_config_with_options_against_other_solvers(tmp_path):
    path = config_with_options(tmp_path)
    out = tmp_path / "bench"
    code = main(["bench", str(path), "--solvers", "qp:osqp,nullspace", "--out", str(out),
                 "--duration", "0.062", "--no-plots", "--quiet"])
    assert code == 0


def test_parse_solver_options():
    got = parse_solver_options(["qp:osqp.eps_abs=1e-9", "qp:osqp.max_iter=200",
                                "nullspace.feasibility_tol=1e-12", "qp:osqp.polishing=true",
                                "qp:osqp.max_iter=300"])
    assert got == {"qp:osqp": {"eps_abs": 1e-9, "max_iter": 300, "polishing": True},
                   "nullspace": {"feasibility_tol": 1e-12}}
    assert isinstance(got["qp:osqp"]["eps_abs"], float)  # YAML 1.1 would read text
    assert parse_solver_options(None) == {}
    if "qp:proxsuite" in available_solvers():  # an alias resolves to the registry name
        assert parse_solver_options(["qp:proxqp.eps_abs=1e-8"]) == {
            "qp:proxsuite": {"eps_abs": 1e-8}}
        assert options_for("qp:proxqp", {"qp:proxsuite": {"eps_abs": 1.0}}) == {
            "eps_abs": 1.0}


@pytest.mark.parametrize(("item", "words"), [
    ("qp:osqp", "SOLVER.OPTION=VALUE"),
    ("qp:osqp.eps_abs", "SOLVER.OPTION=VALUE"),
    ("qp:osqp.=1", "SOLVER.OPTION=VALUE"),
    (".eps=1", "SOLVER.OPTION=VALUE"),
    ("qp:osqp.eps-abs=1", "not an option name"),
    ("qp:osqp.eps_abs=[1, 2]", "single value"),
    ("qp:nope.eps_abs=1", "unknown solver"),
])
def test_malformed_solver_option_flags(item, words):
    with pytest.raises(InvalidInputError, match=words) if "unknown" not in words else \
            pytest.raises(Exception, match=words):
        parse_solver_options([item])


def test_solver_option_reaches_the_solver(tmp_path):
    path = config_with_options(tmp_path)
    cli = parse_solver_options(["qp:osqp.eps_abs=1e-8", "nullspace.max_iter=50"])
    exp = build_experiment(load_config(path), str(path), solver_options=cli)
    assert exp.solver_options == {"eps_abs": 1e-8, "max_iter": 123}  # flag over file
    ns = build_experiment(load_config(path), str(path), solver="nullspace",
                          solver_options=cli)
    assert ns.solver_options == {"max_iter": 50}
    assert ns.controller().solver.max_iter == 50


def test_solver_option_via_cli_is_recorded(tmp_path):
    path = config_with_options(tmp_path)
    out = tmp_path / "o"
    assert main(["run", str(path), "--solver", "nullspace", "--solver-option",
                 "nullspace.max_iter=77", "--out", str(out), "--quiet", "--no-plots"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["solver_options"] == {"max_iter": 77}


@pytest.mark.parametrize(("flag", "words"), [
    ("qp:osqp.eps_abs=-1", ["--solver-option qp:osqp.eps_abs", ">= 0"]),
    ("qp:osqp.max_iter=0", ["--solver-option qp:osqp.max_iter", ">= 1"]),
    ("qp:osqp.not_an_option=1", ["--solver-option qp:osqp.not_an_option", "eps_rel"]),
    ("qp:osqp.max_iter=many", ["expected an integer"]),
    ("nullspace.max_iter=5", ["does not run here", "qp:osqp"]),
])
def test_bad_solver_option_flags_exit_2(tmp_path, capsys, flag, words):
    path = config_with_options(tmp_path)
    out = tmp_path / "o"
    assert main(["run", str(path), "--solver-option", flag, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
    for word in words:
        assert word in err
    assert not out.exists()


def test_bench_refuses_options_of_a_solver_not_benched(tmp_path, capsys):
    path = config_with_options(tmp_path)
    assert main(["bench", str(path), "--solvers", "nullspace", "--solver-option",
                 "qp:osqp.eps_abs=1e-9", "--out", str(tmp_path / "b")]) == 2
    assert "does not run here" in capsys.readouterr().err


def test_check_solver_options_names_the_flag():
    with pytest.raises(SolverFlagError, match=r"--solver-option nullspace\.max_iter"):
        check_solver_options({"nullspace": {"max_iter": 0}})
    check_solver_options({"nullspace": {"max_iter": 3}}, used=["nullspace"])


def test_file_option_errors_name_the_key_and_the_valid_names(tmp_path):
    d = yaml.safe_load(PAPER.read_text())
    d["solver"] = {"name": "nullspace", "options": {"maxiter": 5}}
    with pytest.raises(ConfigError) as info:
        build_experiment(parse_config(d, "f.yaml"), "f.yaml")
    assert info.value.key == "solver.options.maxiter"
    assert "max_iter" in info.value.valid


@pytest.mark.parametrize("backend", ["osqp", "proxqp", "daqp", "piqp", "clarabel", "highs"])
def test_backend_option_names_are_the_installed_packages(backend):
    names = backend_options(backend)
    if names is None:
        pytest.skip(f"{backend} not installed")
    assert "verbose" not in names  # dualarm-qp keeps the backends silent
    expected = {"osqp": {"eps_abs", "max_iter", "polishing", "rho"},
                "proxqp": {"eps_abs", "max_iter", "max_iter_in", "compute_preconditioner"},
                "daqp": {"primal_tol", "iter_limit", "time_limit"},
                "piqp": {"eps_abs", "eps_rel", "max_iter"},
                "clarabel": {"max_iter", "time_limit", "tol_feas"},
                "highs": {"time_limit", "qp_iteration_limit",
                          "primal_feasibility_tolerance"}}[backend]
    assert expected <= set(names)


@pytest.mark.parametrize(("solver", "options", "option"), [
    ("qp:piqp", {"not_an_option": 1}, "not_an_option"),
    ("qp:highs", {"not_an_option": 1}, "not_an_option"),
    ("qp:highs", {"time_limit": "soon"}, "time_limit"),
    ("qp:highs", {"qp_iteration_limit": -3}, "qp_iteration_limit"),
    ("qp:piqp", {"max_iter": 2.5}, "max_iter"),
    ("qp:osqp", {"verbose": True}, "verbose"),
    ("qp:clarabel", {"direct_solve_method": "nope"}, "direct_solve_method"),
    ("qp:daqp", {"primal_tol": float("inf")}, "primal_tol"),
    ("qp:proxsuite", {"max_iter": 0}, "max_iter"),
    ("sns", {"feasibility_tol": 0.0}, "feasibility_tol"),
    ("nullspace", {"max_iter": True}, "max_iter"),
    ("reference", {"tol": 1e-3}, "tol"),
])
def test_options_are_checked_when_the_solver_is_built(solver, options, option):
    if solver not in available_solvers():
        pytest.skip(f"{solver} not installed")
    with pytest.raises(SolverOptionError) as info:
        get_solver(solver, **options)
    assert info.value.option == option


@pytest.mark.parametrize(("solver", "options"), [
    ("qp:highs", {"time_limit": 2, "presolve": "off"}),
    ("qp:piqp", {"eps_abs": 1e-7, "max_iter": 50}),
    ("qp:clarabel", {"max_iter": 50, "tol_feas": 1e-7}),
    ("qp:daqp", {"iter_limit": 500}),
    ("qp:proxsuite", {"eps_abs": 1e-8, "max_iter_in": 50}),
    ("qp:osqp", {"polishing": False, "time_limit": 0.5}),
])
def test_valid_options_reach_the_backend(solver, options):
    if solver not in available_solvers():
        pytest.skip(f"{solver} not installed")
    s = get_solver(solver, **options)
    for key, value in options.items():
        assert s.options[key] == value  # type: ignore[attr-defined]


def test_a_run_with_a_solver_option_judges_it_once(tmp_path, monkeypatch):
    """The options are validated once at the boundary: one probe solve for the whole run,
    and the controller the command line built is the one that runs."""
    import dualarm_qp.solvers.qp as qp
    from dualarm_qp.cli import main

    qp._JUDGED.clear()
    probes = []
    real = qp.QPSolver._probe
    monkeypatch.setattr(qp.QPSolver, "_probe",
                        lambda self, opts: probes.append(opts) or real(self, opts))
    config = Path(__file__).resolve().parents[2] / "configs" / "puma_beam_limits.yaml"
    code = main(["run", str(config), "--solver", "qp:daqp", "--solver-option",
                 "qp:daqp.primal_tol=1e-9", "--out", str(tmp_path / "run"), "--no-plots",
                 "--quiet"])
    assert code == 0
    assert len(probes) == 1
