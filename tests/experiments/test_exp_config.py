"""Experiment files: unit conversion on load and clear errors for bad input."""

from __future__ import annotations

import copy
import math
from pathlib import Path

import numpy as np
import pytest
import yaml

from dualarm_qp.errors import ConfigError, InvalidInputError
from dualarm_qp.experiments import build_experiment, load_config, parse_config

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
PAPER = CONFIGS / "puma_beam_sliding_s7_100.yaml"


def paper_dict():
    return yaml.safe_load(PAPER.read_text())


def test_paper_config_converts_to_si():
    exp = build_experiment(load_config(PAPER), str(PAPER))
    assert exp.options.dt == pytest.approx(0.031)
    assert exp.duration == pytest.approx(15.5)
    np.testing.assert_allclose(exp.initial.q_f[:3], np.deg2rad([-164.1774, 32.065, -30.9446]))
    assert exp.initial.sigma == pytest.approx(0.45)
    assert exp.task.surface.r_max[2] == pytest.approx(0.4)
    assert exp.options.grasp_weight == pytest.approx(100.0)  # grasp_unit: m
    D0 = exp.task.trajectory.pose(0.0)
    np.testing.assert_allclose(D0[:3, 3], [-0.0003, 0.690, 0.2604])
    v = exp.task.trajectory.twist(1.0)[:3]
    np.testing.assert_allclose(v, [1 / 31, 0, 0])  # 1 mm per 31 ms
    # The follower base is recovered as a near-pure translation of about (300, 1380, 0) mm.
    base = exp.task.follower.base
    np.testing.assert_allclose(base[:3, 3], [0.3, 1.38, 0.0], atol=1e-3)
    assert np.allclose(base[:3, :3], np.eye(3), atol=1e-4)
    # The closure holds at t0 by construction.
    dp, dw = exp.task.closure_error(exp.initial.q_l, exp.initial.q_f, exp.initial.sigma)
    assert dp < 1e-12 and dw < 1e-12


def test_grasp_weight_follows_its_unit():
    d = paper_dict()
    d["controller"]["weights"] = {"joints": 1, "grasp": 100, "grasp_unit": "mm"}
    assert build_experiment(parse_config(d)).options.grasp_weight == pytest.approx(1e8)
    d["controller"]["weights"] = {"joints": 1, "grasp": 100}  # the file's unit: mm
    assert build_experiment(parse_config(d)).options.grasp_weight == pytest.approx(1e8)


def test_units_in_metres_and_radians_give_the_same_experiment():
    d = paper_dict()
    m = copy.deepcopy(d)
    m["units"] = {"length": "m", "angle": "rad", "time": "s"}
    mm, deg = 1e-3, math.pi / 180
    m["follower"]["initial"]["joints"] = [q * deg for q in d["follower"]["initial"]["joints"]]
    m["object"]["surface"]["r_max"] = [v * mm for v in d["object"]["surface"]["r_max"]]
    m["object"]["grasp_initial"] = d["object"]["grasp_initial"] * mm
    m["trajectory"]["start"]["position"] = [v * mm for v in d["trajectory"]["start"]["position"]]
    m["trajectory"]["velocity"] = [v * mm for v in d["trajectory"]["velocity"]]
    a, b = build_experiment(parse_config(d)), build_experiment(parse_config(m))
    np.testing.assert_allclose(a.task.follower.base, b.task.follower.base, atol=1e-12)
    np.testing.assert_allclose(a.initial.q_l, b.initial.q_l, atol=1e-12)
    assert a.options.dt == b.options.dt
    assert a.options.grasp_weight == pytest.approx(b.options.grasp_weight)
    np.testing.assert_allclose(a.initial.q_f, b.initial.q_f, atol=1e-15)


@pytest.mark.parametrize(
    ("mutate", "key", "fragment"),
    [
        (lambda d: d["controller"].update(dtt=0.1), "controller.dtt", "valid: dt, duration"),
        (lambda d: d.update(solvr={}), "solvr", "valid: name, description, units"),
        (lambda d: d["leader"].update(preset="puma"), "leader.preset", "valid: puma560"),
        (lambda d: d["controller"].update(dt="fast"), "controller.dt", "valid number"),
        (lambda d: d.pop("object"), "object", "missing"),
        (lambda d: d["units"].update(length="inch"), "units.length", "valid: m, mm"),
        (lambda d: d["controller"].update(dt=-1), "controller", "positive"),
        (lambda d: d["controller"]["weights"].update(grasp=0), "controller.weights", "> 0"),
        (lambda d: d["follower"]["initial"].update(joints=[0, 0]), "follower.initial.joints",
         "6 values"),
    ],
)
def test_bad_config_names_file_and_key(tmp_path, mutate, key, fragment):
    d = paper_dict()
    mutate(d)
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(d))
    with pytest.raises(ConfigError) as info:
        build_experiment(load_config(path), str(path))
    msg = str(info.value)
    assert str(path) in msg
    assert f"'{key}'" in msg or key in msg
    assert fragment in msg


def test_missing_file_and_bad_yaml(tmp_path):
    with pytest.raises(ConfigError, match="file not found"):
        load_config(tmp_path / "nope.yaml")
    bad = tmp_path / "broken.yaml"
    bad.write_text("controller: [1, 2\n")
    with pytest.raises(ConfigError, match="not valid YAML at line"):
        load_config(bad)
    top = tmp_path / "list.yaml"
    top.write_text("- 1\n- 2\n")
    with pytest.raises(ConfigError, match="mapping"):
        load_config(top)


def test_invalid_leader_branch_lists_the_valid_ones():
    d = paper_dict()
    d["leader"]["initial"]["ik_branch"] = {"arm": -1, "elbow": -1, "wrist": -1}
    with pytest.raises(ConfigError, match="valid: arm="):
        build_experiment(parse_config(d), "x.yaml")


def test_misspelt_required_key_is_named_with_the_valid_keys(tmp_path):
    d = paper_dict()
    d["controller"]["dtt"] = d["controller"].pop("dt")
    path = tmp_path / "typo.yaml"
    path.write_text(yaml.safe_dump(d))
    with pytest.raises(ConfigError) as info:
        load_config(path)
    assert "controller.dtt" in str(info.value) and "valid: dt," in str(info.value)


def test_nan_joints_and_bad_values_name_their_key(tmp_path):
    d = paper_dict()
    d["follower"]["initial"]["joints"][2] = float("nan")
    with pytest.raises(ConfigError, match=r"follower\.initial\.joints"):
        build_experiment(parse_config(d), "x.yaml")
    d = paper_dict()
    d["controller"]["dt"] = -0.031
    with pytest.raises(ConfigError) as info:
        parse_config(d, "x.yaml")
    msg = str(info.value)
    assert "controller.dt" in msg and "positive" in msg and "weights" not in msg


def test_bundled_configs_are_the_repository_configs():
    """`dualarm-qp reproduce` runs the package's copies: they must be these files."""
    from dualarm_qp.experiments.reproduce import BENCH_CONFIGS, CASES, bundled_config

    for name in [*(name for _, name in CASES), *BENCH_CONFIGS]:
        assert bundled_config(name).read_bytes() == (CONFIGS / name).read_bytes()


def _built(mutate, solver=None):
    d = paper_dict()
    mutate(d)
    return build_experiment(parse_config(d, "x.yaml"), "x.yaml", solver=solver)


def test_run_limits_convert_to_si():
    def mutate(d):
        d["controller"].update(tracking_tolerance=[2, 1], closure_tolerance=[3, 2],
                               singular_value_min=0.01, singularity_action="stop",
                               duration_cap=40)

    exp = _built(mutate)
    assert exp.limits.tracking == pytest.approx((0.002, math.radians(1)))
    assert exp.limits.closure == pytest.approx((0.003, math.radians(2)))
    assert exp.limits.singular_value_min == 0.01
    assert exp.limits.singularity_action == "stop"
    assert exp.limits.duration_cap == pytest.approx(40.0)


@pytest.mark.parametrize(("key", "value", "words"), [
    ("duration_cap", 1.0, "at least the duration"),
    ("singularity_action", "panic", "warn"),
    ("singular_value_min", -1.0, ">= 0"),
    ("tracking_tolerance", [0, 1], "positive"),
])
def test_bad_run_limits_name_the_key(key, value, words):
    def mutate(d):
        d["controller"][key] = value

    with pytest.raises(ConfigError, match=words) as err:
        _built(mutate)
    assert "controller" in str(err.value)


def test_projection_is_refused_for_a_hard_limit_solver():
    def mutate(d):
        d["controller"]["projection"] = True

    with pytest.raises(ConfigError, match=r"controller\.projection"):
        _built(mutate, solver="nullspace")
    assert _built(mutate).project is True  # the paper's reference step may use it


@pytest.mark.parametrize(("fallback", "ok"), [("nullspace", True), ("none", True),
                                               ("qp:daqp", True), ("reference", False),
                                               ("qp:nope", False)])
def test_fallback_must_keep_hard_limits(fallback, ok):
    def mutate(d):
        d["solver"]["fallback"] = fallback

    if ok:
        exp = _built(mutate, solver="qp:osqp")
        ctrl = exp.controller()
        assert (ctrl.fallback is None) == (fallback == "none")
        assert exp.controller(fallback=False).fallback is None
    else:
        with pytest.raises(ConfigError, match=r"solver\.fallback"):
            _built(mutate)


# --- the follower's start: explicit base, IK branch, near ---------------------------------

def _recovered_base() -> dict:
    """The follower base that 'base: auto' recovers for the paper's case, in file units."""
    exp = build_experiment(parse_config(paper_dict()))
    base = exp.task.follower.base
    return {"position": (base[:3, 3] * 1e3).tolist(), "rotation": base[:3, :3].tolist()}


def test_explicit_base_matching_the_joints_is_accepted():
    d = paper_dict()
    d["follower"]["base"] = _recovered_base()
    exp = build_experiment(parse_config(d))
    dp, dw = exp.task.closure_error(exp.initial.q_l, exp.initial.q_f, exp.initial.sigma)
    assert dp < 1e-9 and dw < 1e-9


@pytest.mark.parametrize(("shift_mm", "turn_deg", "words"), [
    ((5.0, 0.0, 0.0), 0.0, "5.000 mm and 0.000 deg"),
    ((0.0, 0.0, 0.0), 0.3, "0.300 deg"),
])
def test_follower_base_mismatch_is_a_config_error_in_mm_and_deg(shift_mm, turn_deg, words):
    d = paper_dict()
    base = _recovered_base()
    base["position"] = [p + s for p, s in zip(base["position"], shift_mm, strict=True)]
    R = np.asarray(base["rotation"])
    t = math.radians(turn_deg)
    Rz = np.array([[math.cos(t), -math.sin(t), 0], [math.sin(t), math.cos(t), 0], [0, 0, 1]])
    base["rotation"] = (Rz @ R).tolist()
    d["follower"]["base"] = base
    with pytest.raises(ConfigError) as info:
        build_experiment(parse_config(d, "x.yaml"), "x.yaml")
    msg = str(info.value)
    assert info.value.key == "follower.base"
    assert words in msg and "allowed: 1 mm, 0.1 deg" in msg


def test_follower_ik_branch_start_closes_the_grasp():
    from dualarm_qp.kinematics.puma_ik import puma560_ik

    d = paper_dict()
    d["follower"]["base"] = _recovered_base()
    exp = build_experiment(parse_config(d))
    target = exp.task.follower_target(exp.initial.q_l, exp.initial.sigma)
    branches = puma560_ik(exp.task.follower, target)
    assert branches
    for sol in branches:
        d["follower"]["initial"] = {"ik_branch": {"arm": sol.arm, "elbow": sol.elbow,
                                                  "wrist": sol.wrist}}
        e = build_experiment(parse_config(d))
        dp, dw = e.task.closure_error(e.initial.q_l, e.initial.q_f, e.initial.sigma)
        assert dp < 1e-9 and dw < 1e-9
        assert e.notes["follower_ik_branch"] == {"arm": sol.arm, "elbow": sol.elbow,
                                                 "wrist": sol.wrist}
    # Table 2's own configuration is off its range (joint 3), so no branch is it.


def test_follower_near_start_solves_from_the_given_joints():
    """Table 2's joints, recovered from 3 deg away (off the range: limits not imposed)."""
    d = paper_dict()
    d["follower"]["base"] = _recovered_base()
    table2 = d["follower"]["initial"]["joints"]
    d["follower"]["initial"] = {"near": [q + 3.0 for q in table2]}
    e = build_experiment(parse_config(d))
    dp, dw = e.task.closure_error(e.initial.q_l, e.initial.q_f, e.initial.sigma)
    assert dp < 1e-9 and dw < 1e-9
    np.testing.assert_allclose(e.initial.q_f, np.deg2rad(table2), atol=1e-4)


def test_leader_near_start_reaches_d_t0():
    d = paper_dict()
    ref = build_experiment(parse_config(d))
    d["leader"]["initial"] = {"near": (np.rad2deg(ref.initial.q_l) + 2.0).tolist()}
    e = build_experiment(parse_config(d))
    np.testing.assert_allclose(e.initial.q_l, ref.initial.q_l, atol=1e-8)


def test_follower_ik_branch_needs_an_explicit_base():
    d = paper_dict()
    d["follower"]["initial"] = {"ik_branch": {"arm": 1, "elbow": 1, "wrist": 1}}
    with pytest.raises(ConfigError, match="ambiguous") as info:
        build_experiment(parse_config(d, "x.yaml"), "x.yaml")
    assert info.value.key == "follower.initial.ik_branch"


# --- names, caps ----------------------------------------------------------------------------

@pytest.mark.parametrize(("name", "safe"), [
    ("../../escape", "_.._escape"),
    ("/etc/passwd", "_etc_passwd"),
    ("beam s7=100", "beam_s7_100"),
    ("..", "experiment"),
    ("a\x00b", "a_b"),
    ("puma_beam_sliding_s7_100", "puma_beam_sliding_s7_100"),
    ("x" * 300, "x" * 100),
])
def test_safe_name_is_one_file_name_component(name, safe):
    from dualarm_qp.experiments.config import safe_name

    got = safe_name(name)
    assert got == safe
    assert "/" not in got and "\x00" not in got and not got.startswith(".")


def test_run_folder_stays_inside_runs(tmp_path, monkeypatch):
    from dualarm_qp.cli import main

    d = paper_dict()
    d["name"] = "../../escape"
    d["controller"]["duration"] = 0.062
    path = tmp_path / "escape.yaml"
    path.write_text(yaml.safe_dump(d))
    work = tmp_path / "a" / "b"
    work.mkdir(parents=True)
    monkeypatch.chdir(work)
    assert main(["run", str(path), "--quiet", "--no-plots"]) == 0
    assert (work / "runs" / "_.._escape" / "reference" / "summary.json").is_file()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a", "escape.yaml"]
    assert sorted(p.name for p in work.iterdir()) == ["runs"]


def test_nul_in_the_name_is_refused():
    d = paper_dict()
    d["name"] = "run\x00"
    with pytest.raises(ConfigError, match="control character") as info:
        parse_config(d, "x.yaml")
    assert info.value.key == "name"


def test_sample_cap_and_short_duration():
    from dualarm_qp.experiments.config import MAX_SAMPLES

    d = paper_dict()
    d["controller"]["dt"] = 2 * d["controller"]["duration"] / MAX_SAMPLES  # exactly the cap
    parse_config(d)
    d["controller"]["dt"] /= 1.01
    with pytest.raises(ConfigError, match="2,000,000") as info:
        parse_config(d)
    assert info.value.key == "controller.dt"
    d = paper_dict()
    d["controller"]["duration"] = d["controller"]["dt"]  # one step: allowed
    parse_config(d)
    d["controller"]["duration"] = d["controller"]["dt"] / 2
    with pytest.raises(ConfigError, match="shorter than one sample"):
        parse_config(d)


def test_numbers_in_yaml_1_2_notation_are_numbers(tmp_path):
    text = PAPER.read_text().replace("dt: 0.031 ", "dt: 31e-3 ")
    assert "31e-3" in text
    path = tmp_path / "exp.yaml"
    path.write_text(text)
    assert load_config(path).controller.dt == pytest.approx(0.031)


def test_yaml_booleans_are_only_true_and_false(tmp_path):
    """YAML 1.2: `velocity_limits: yes` (YAML 1.1's true) is refused, naming the key."""
    text = (CONFIGS / "puma_beam_limits.yaml").read_text()
    assert "velocity_limits: true" in text
    path = tmp_path / "yes.yaml"
    path.write_text(text.replace("velocity_limits: true", "velocity_limits: yes"))
    with pytest.raises(ConfigError, match=r"controller\.velocity_limits"):
        load_config(path)
    path.write_text(text.replace("velocity_limits: true", "velocity_limits: false"))
    assert load_config(path).controller.velocity_limits is False


def test_dt_argument_replaces_the_files_sampling_interval():
    """``build_experiment(..., dt=)`` (a 1 kHz loop on a file sampled at 31 ms)."""
    cfg = load_config(PAPER)  # dt 31 ms, gains given, no centring horizon
    exp = build_experiment(cfg, str(PAPER), dt=1e-3)
    assert exp.options.dt == 1e-3
    assert exp.options.centre_horizon == 1e-3  # its default, dt, follows it
    assert exp.options.correction_gain == pytest.approx(1 / 0.031)  # the file's gain stays
    assert exp.duration == pytest.approx(15.5)  # the path is the file's
    assert build_experiment(cfg, str(PAPER)).options.dt == pytest.approx(0.031)


@pytest.mark.parametrize("dt", [0.0, -1e-3, 1e-9, math.nan, math.inf])
def test_a_bad_dt_argument_is_refused(dt):
    with pytest.raises(InvalidInputError, match="dt must be a sampling interval"):
        build_experiment(load_config(PAPER), str(PAPER), dt=dt)
