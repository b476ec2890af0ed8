"""Every malformed experiment file is bad input: exit 2, one line naming file and key.

Each case below writes one malformed file into ``tmp_path`` and runs
``dualarm-qp run FILE --out OUT``: the exit code is 2, stderr is one line that names the
file and (when the file has keys at all) the offending key, with no traceback and no
"internal error", and no output folder is written.
"""

from __future__ import annotations

import copy
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
import yaml

from dualarm_qp.cli import main
from dualarm_qp.solvers import available_solvers

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
PAPER = CONFIGS / "puma_beam_sliding_s7_100.yaml"
CURVED = CONFIGS / "curved_bar_waypoints.yaml"

_BASE = {"paper": yaml.safe_load(PAPER.read_text()),
         "curved": yaml.safe_load(CURVED.read_text())}

#: The PUMA 560 of Table 1 as a plain DH table (mm, deg): no acceleration limits.
PUMA_DH = [[0, -90, 0], [431.8, 0, 149.09], [-20.32, 90, 0], [0, -90, 433.07], [0, 90, 0],
           [0, 0, 56.25]]

#: A follower base that is 50 mm and 2 deg away from the one that closes the grasp.
WRONG_BASE = {"position": [350, 1380, 0], "rpy": [0, 0, 2]}


def _set(path: str, value: Any) -> Callable[[dict[str, Any]], None]:
    """Mutation setting the dotted key ``path`` (list indices as numbers) to ``value``."""
    def mutate(d: dict[str, Any]) -> None:
        parts = path.split(".")
        node: Any = d
        for part in parts[:-1]:
            node = node[int(part)] if isinstance(node, list) else node.setdefault(part, {})
        last = parts[-1]
        if isinstance(node, list):
            node[int(last)] = value
        else:
            node[last] = value
    return mutate


def _all(*mutations: Callable[[dict[str, Any]], None]) -> Callable[[dict[str, Any]], None]:
    def mutate(d: dict[str, Any]) -> None:
        for m in mutations:
            m(d)
    return mutate


def auto_base() -> dict[str, Any]:
    """A follower base placeholder for DH-arm cases (any explicit pose)."""
    return {"position": [300, 1380, 0]}


def _paper_text() -> str:
    return PAPER.read_text(encoding="utf-8")


# (id, base config or raw bytes maker, mutation, key expected in the message or None,
#  words expected in the message, solvers the case needs)
Case = tuple[str, str, Any, str | None, tuple[str, ...], tuple[str, ...]]

CASES: list[Case] = [
    # --- the file itself ---------------------------------------------------------------
    ("encoding-utf16-bom", "raw", lambda: _paper_text().encode("utf-16"), None,
     ("UTF-16", "UTF-8"), ()),
    ("encoding-utf16-no-bom", "raw", lambda: _paper_text().encode("utf-16-le"), None,
     ("NUL", "UTF-8"), ()),
    ("encoding-latin1-value", "raw",
     lambda: _paper_text().replace('"Paper case (b)', '"Caf\xe9 (b)').encode("latin-1"),
     "description", ("not UTF-8", "line 6"), ()),
    ("encoding-bad-byte-in-name", "raw",
     lambda: _paper_text().encode().replace(b"name: puma", b"name: \xff\xfepuma"),
     "name", ("not UTF-8", "0xff"), ()),
    ("deep-nesting-options", "raw",
     lambda: (_paper_text() + "  options: {x: " + "[" * 5000 + "]" * 5000 + "}\n").encode(),
     "solver.options.x", ("nested more than",), ()),
    ("deep-nesting-mappings", "raw",
     lambda: (_paper_text().replace('description: "Paper case (b): sliding grasp, s7 = 100"',
                                    "description: " + "{a: " * 3000 + "1" + "}" * 3000)
              ).encode(),
     "description", ("nested more than",), ()),
    ("top-level-list", "raw", lambda: b"- 1\n- 2\n", None, ("mapping", "list"), ()),
    ("top-level-scalar", "raw", lambda: b"just some text\n", None, ("mapping", "text"), ()),
    ("empty-file", "raw", lambda: b"", None, ("mapping", "empty"), ()),
    ("duplicate-key", "raw",
     lambda: _paper_text().replace("  dt: 0.031", "  dt: 0.031\n  dt: 0.05").encode(),
     "controller.dt", ("given twice",), ()),
    ("broken-yaml", "raw", lambda: _paper_text().replace("weights: {", "weights: [{").encode(),
     None, ("not valid YAML", "line"), ()),
    ("python-tag", "raw",
     lambda: _paper_text().replace('description: "Paper case (b): sliding grasp, s7 = 100"',
                                   "description: !!python/object/apply:os.getcwd []").encode(),
     None, ("not valid YAML",), ()),
    ("section-not-mapping", "paper", _set("controller", 5), "controller",
     ("mapping", "dt"), ()),
    ("unknown-nested-key", "paper", _set("object.surface.r_mid", [0, 0, 1]),
     "object.surface.r_mid", ("unknown key", "r_min"), ()),
    # --- lengths against the arm's joint count --------------------------------------------
    ("weights-joints-5-of-6", "paper", _set("controller.weights.joints", [1, 1, 1, 1, 1]),
     "controller.weights.joints", ("6",), ()),
    ("follower-q_min-5", "paper", _set("follower.q_min", [-1, -1, -1, -1, -1]),
     "follower.q_min", ("6 values",), ()),
    ("follower-q_max-7", "paper", _set("follower.q_max", [1] * 7), "follower.q_max",
     ("6 values",), ()),
    ("leader-qd_max-5", "paper", _set("leader.qd_max", [1] * 5), "leader.qd_max",
     ("6 values",), ()),
    ("leader-initial-joints-5", "paper", _set("leader.initial", {"joints": [0] * 5}),
     "leader.initial.joints", ("6 values",), ()),
    ("follower-initial-joints-7", "paper",
     _set("follower.initial.joints", [0, 0, 0, 0, 0, 0, 0]), "follower.initial.joints",
     ("6 values",), ()),
    ("q_min-above-q_max", "paper",
     _all(_set("follower.q_min", [-100] * 6), _set("follower.q_max", [100, 100, -120, 100, 100,
                                                                        100])),
     "follower.q_min", ("joint 3", "above q_max"), ()),
    ("qd_max-zero", "paper", _set("follower.qd_max", [100, 100, 0, 100, 100, 100]),
     "follower.qd_max", ("joint 3", "> 0"), ()),
    ("dh-arm-too-short", "paper",
     _set("follower", {"dh": {"rows": [[0, 0, 0], [300, 0, 0]]}, "base": auto_base(),
                       "initial": {"joints": [0, 0]}}),
     "follower.dh.rows", ("2 joints", "at least 5"), ()),
    # --- sample count and duration -------------------------------------------------------
    ("dt-1e-9-sample-cap", "paper", _set("controller.dt", 1e-9), "controller.dt",
     ("samples", "2,000,000"), ()),
    ("duration_cap-sample-cap", "paper", _set("controller.duration_cap", 1e6),
     "controller.dt", ("samples",), ()),
    ("duration-shorter-than-dt", "paper", _set("controller.duration", 0.01),
     "controller.duration", ("shorter than one sample",), ()),
    # --- booleans and text where numbers belong -----------------------------------------------
    ("dt-true", "paper", _set("controller.dt", True), "controller.dt", ("not true",), ()),
    ("duration-false", "paper", _set("controller.duration", False), "controller.duration",
     ("not false",), ()),
    ("grasp_initial-true", "paper", _set("object.grasp_initial", True),
     "object.grasp_initial", ("not true",), ()),
    ("weights-grasp-true", "paper", _set("controller.weights.grasp", True),
     "controller.weights.grasp", ("not true",), ()),
    ("weights-joints-list-bool", "paper", _set("controller.weights.joints", [1, True, 1]),
     "controller.weights.joints.1", ("not true",), ()),
    ("dt-below-a-microsecond", "paper",
     lambda d: d["controller"].update(dt=1e-300, duration=1e-300),
     "controller.dt", ("shortest sampling interval",), ()),
    ("q-max-minus-inf", "paper", _set("follower.q_max", [-1e999] * 6),
     "follower.q_max", ("no joint can reach",), ()),
    ("velocity-limits-yes", "paper", _set("controller.velocity_limits", "yes"),
     "controller.velocity_limits", ("boolean",), ()),
    ("velocity-bool", "paper", _set("trajectory.velocity", [True, 0, 0]),
     "trajectory.velocity.0", ("not true",), ()),
    ("base-position-bool", "paper", _set("leader.base.position", [0, False, 0]),
     "leader.base.position.1", ("not false",), ()),
    ("ik-branch-bool", "paper", _set("leader.initial.ik_branch.arm", True),
     "leader.initial.ik_branch.arm", ("+1 or -1",), ()),
    ("dt-quoted-text", "paper", _set("controller.dt", "0.031"), "controller.dt",
     ("not text",), ()),
    # --- NaN and infinity ------------------------------------------------------------------
    ("grasp_initial-nan", "paper", _set("object.grasp_initial", float("nan")),
     "object.grasp_initial", ("finite",), ()),
    ("velocity-nan", "paper", _set("trajectory.velocity", [float("nan"), 0, 0]),
     "trajectory.velocity.0", ("finite",), ()),
    ("start-position-inf", "paper", _set("trajectory.start.position", [0, float("inf"), 0]),
     "trajectory.start.position.1", ("finite",), ()),
    ("H1-rpy-nan", "paper", _set("object.H1.rpy", [0, float("nan"), 0]), "object.H1.rpy.1",
     ("finite",), ()),
    ("correction_gain-inf", "paper", _set("controller.correction_gain", float("inf")),
     "controller.correction_gain", ("finite",), ()),
    ("grasp_initial-1e308", "paper", _set("object.grasp_initial", 1e308),
     "object.grasp_initial", ("between -1e+12 and 1e+12",), ()),
    ("q_min-nan", "paper", _set("follower.q_min", [float("nan")] * 6), "follower.q_min.0",
     ("NaN",), ()),
    # --- solver options (checked when the solver is built) ----------------------------------
    ("osqp-max_iter-0", "paper", _set("solver", {"name": "qp:osqp", "options": {"max_iter": 0}}),
     "solver.options.max_iter", (">= 1",), ("qp:osqp",)),
    ("osqp-negative-eps", "paper",
     _set("solver", {"name": "qp:osqp", "options": {"eps_abs": -1e-6}}),
     "solver.options.eps_abs", (">= 0",), ("qp:osqp",)),
    ("osqp-alpha-out-of-range", "paper",
     _set("solver", {"name": "qp:osqp", "options": {"alpha": 5.0}}),
     "solver.options.alpha", ("refuses",), ("qp:osqp",)),
    ("piqp-unknown-option", "paper",
     _set("solver", {"name": "qp:piqp", "options": {"not_an_option": 1}}),
     "solver.options.not_an_option", ("unknown option", "eps_abs"), ("qp:piqp",)),
    ("highs-unknown-option", "paper",
     _set("solver", {"name": "qp:highs", "options": {"not_an_option": 1}}),
     "solver.options.not_an_option", ("unknown option", "time_limit"), ("qp:highs",)),
    ("highs-wrong-type", "paper",
     _set("solver", {"name": "qp:highs", "options": {"qp_iteration_limit": "many"}}),
     "solver.options.qp_iteration_limit", ("expected an integer",), ("qp:highs",)),
    ("daqp-float-iterations", "paper",
     _set("solver", {"name": "qp:daqp", "options": {"iter_limit": 1.5}}),
     "solver.options.iter_limit", ("expected an integer",), ("qp:daqp",)),
    ("clarabel-bool-iterations", "paper",
     _set("solver", {"name": "qp:clarabel", "options": {"max_iter": True}}),
     "solver.options.max_iter", ("expected an integer",), ("qp:clarabel",)),
    ("proxsuite-nan-eps", "paper",
     _set("solver", {"name": "qp:proxsuite", "options": {"eps_abs": float("nan")}}),
     "solver.options.eps_abs", ("finite",), ("qp:proxsuite",)),
    ("quadprog-any-option", "paper",
     _set("solver", {"name": "qp:quadprog", "options": {"eps": 1e-9}}),
     "solver.options.eps", ("unknown option", "no options"), ("qp:quadprog",)),
    ("nullspace-max_iter-0", "paper",
     _set("solver", {"name": "nullspace", "options": {"max_iter": 0}}),
     "solver.options.max_iter", (">= 1",), ()),
    ("nullspace-negative-tol", "paper",
     _set("solver", {"name": "nullspace", "options": {"feasibility_tol": -1e-3}}),
     "solver.options.feasibility_tol", ("> 0",), ()),
    ("sns-unknown-option", "paper",
     _set("solver", {"name": "sns", "options": {"max_iter": 10}}),
     "solver.options.max_iter", ("unknown option", "feasibility_tol"), ()),
    ("reference-unknown-option", "paper", _set("solver.options", {"damping": 0.1}),
     "solver.options.damping", ("unknown option", "tol"), ()),
    ("option-not-a-value", "paper",
     _set("solver", {"name": "qp:osqp", "options": {"eps_abs": [1, 2]}}),
     "solver.options.eps_abs", ("single value",), ()),
    ("unknown-solver", "paper", _set("solver.name", "qp:nope"), "solver.name",
     ("unknown solver",), ()),
    # --- the initial state ---------------------------------------------------------------------
    ("follower-base-mismatch", "paper", _set("follower.base", WRONG_BASE), "follower.base",
     ("mm", "deg", "do not close the grasp"), ()),
    ("ik-branch-with-auto-base", "paper",
     _set("follower.initial", {"ik_branch": {"arm": 1, "elbow": 1, "wrist": 1}}),
     "follower.initial.ik_branch", ("ambiguous",), ()),
    ("near-with-auto-base", "paper", _set("follower.initial", {"near": [0] * 6}),
     "follower.initial.near", ("ambiguous",), ()),
    ("follower-branch-out-of-reach", "paper",
     _all(_set("follower.base", {"position": [5000, 0, 0]}),
          _set("follower.initial", {"ik_branch": {"arm": 1, "elbow": 1, "wrist": 1}})),
     "follower.initial.ik_branch", ("out of reach",), ()),
    ("two-initial-forms", "paper",
     _set("follower.initial", {"joints": [0] * 6, "near": [0] * 6}), "follower.initial",
     ("exactly one",), ()),
    ("leader-joints-off-the-path", "paper", _set("leader.initial", {"joints": [0] * 6}),
     "leader.initial.joints", ("mm", "deg", "D(t0)"), ()),
    # --- limits the arms do not state ----------------------------------------------------------
    ("acceleration-limits-dh-arm-without-qdd_max", "paper",
     _all(_set("controller.acceleration_limits", True),
          lambda d: d["follower"].pop("preset"),
          _set("follower.dh", {"rows": PUMA_DH})),
     "follower.qdd_max", ("acceleration_limits", "any joint", "deg/s^2", "6"), ()),
    ("physics-tau_max-wrong-length", "paper", _set("physics", {"tau_max": {"leader": [10, 20]}}),
     "physics.tau_max.leader", ("1 value", "or 6", "got 2"), ()),
    # --- units ---------------------------------------------------------------------------------
    ("metres-in-a-mm-file", "paper", _set("trajectory.start.position", [-0.0003, 0.69, 0.2604]),
     "units.length", ("units may be wrong", "units.length is mm", "trajectory.start"), ()),
    ("mm-in-a-metres-file", "paper", _set("units.length", "m"),
     "units.length", ("units may be wrong", "times the arm's reach", "metres"), ()),
    # --- names, surfaces, paths ---------------------------------------------------------------
    ("name-with-nul", "paper", _set("name", "run\x00x"), "name", ("control character",), ()),
    ("name-only-dots", "paper", _set("name", ".."), "name", ("letter or digit",), ()),
    ("waypoint-times-not-increasing", "curved", _set("trajectory.waypoints.2.t", 3),
     "trajectory.waypoints.2.t", ("strictly increasing",), ()),
    ("grasp-range-reversed", "curved", _set("object.surface.grasp_range", [400, 0]),
     "object.surface.grasp_range", ("min <= max",), ()),
]


def _write(tmp_path: Path, case_id: str, base: str, make: Any) -> Path:
    path = tmp_path / f"{case_id}.yaml"
    if base == "raw":
        path.write_bytes(make())
    else:
        d = copy.deepcopy(_BASE[base])
        make(d)
        path.write_text(yaml.safe_dump(d, allow_unicode=True))
    return path


def test_at_least_forty_cases() -> None:
    assert len(CASES) >= 40
    assert len({c[0] for c in CASES}) == len(CASES)


@pytest.mark.parametrize(("base", "make", "key", "words", "needs"),
                         [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_malformed_file_is_bad_input(tmp_path, monkeypatch, capsys, base, make, key, words,
                                     needs) -> None:
    missing = [s for s in needs if s not in available_solvers()]
    if missing:
        pytest.skip(f"{', '.join(missing)} not installed")
    case_dir = tmp_path / "case"
    case_dir.mkdir()
    monkeypatch.chdir(case_dir)  # a default runs/ folder would appear here
    path = _write(tmp_path, "bad", base, make)
    out = tmp_path / "out"
    code = main(["run", str(path), "--out", str(out), "--quiet", "--no-plots"])
    err = capsys.readouterr().err
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    line = lines[0]
    assert "Traceback" not in err and "internal error" not in err
    assert str(path) in line
    if key is not None:
        assert f"key '{key}'" in line, line
    for word in words:
        assert word in line, (word, line)
    assert not out.exists()
    assert os.listdir(case_dir) == []
