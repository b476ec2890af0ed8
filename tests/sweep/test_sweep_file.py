"""Sweep files: expansion into points, and bad input stopped (exit 2) naming the key."""

from __future__ import annotations

import pytest
import yaml
from sweep_tools import BASE, NEAR, write_sweep

from dualarm_qp.cli import main
from dualarm_qp.errors import ConfigError
from dualarm_qp.sweep.points import point_document, point_key, prepare_points, set_key
from dualarm_qp.sweep.spec import expand, load_sweep, parse_sweep


def test_grid_expands_last_key_fastest_with_every_random_sample():
    spec = parse_sweep({"base": "b.yaml", "grid": {"a.x": [1, 2], "b": ["p", "q", "r"]},
                        "random": {"n": 2, "seed": 3, "c.0": {"uniform": [0, 1]}}}, "s.yaml")
    pts = expand(spec)
    assert len(pts) == 12
    assert [(p.values["a.x"], p.values["b"]) for p in pts[:4]] == [(1, "p"), (1, "p"),
                                                                  (1, "q"), (1, "q")]
    assert [p.index for p in pts] == list(range(12))
    draws = [p.values["c.0"] for p in pts[:2]]
    assert draws[0] != draws[1] and all(0 <= d <= 1 for d in draws)
    assert [p.values["c.0"] for p in pts[2:4]] == draws  # the same samples at every point
    again = expand(spec)
    assert [p.values for p in again] == [p.values for p in pts]  # seeded: resumable


def test_a_paired_key_takes_the_value_at_its_grid_keys_position():
    spec = parse_sweep({"base": "b.yaml", "grid": {"v": [10, 20, 40], "s": ["a", "b"]},
                        "paired": {"v": {"duration": [4, 2, 1], "note": ["x", "y", "z"]}}},
                       "s.yaml")
    pts = expand(spec)
    assert len(pts) == 6  # pairing adds no combination
    assert [(p.values["v"], p.values["duration"], p.values["note"]) for p in pts[::2]] == [
        (10, 4, "x"), (20, 2, "y"), (40, 1, "z")]
    assert all(p.values["v"] * p.values["duration"] == 40 for p in pts)
    assert spec.axes == ["v", "s"] and spec.swept_keys == ["v", "s", "duration", "note"]


def test_random_distributions_are_drawn_as_given():
    spec = parse_sweep({"base": "b.yaml", "random": {
        "n": 200, "seed": 1, "a": {"normal": [10, 0.5]}, "b": {"choice": ["x", "y"]}}},
        "s.yaml")
    pts = expand(spec)
    a = [p.values["a"] for p in pts]
    assert 9.5 < sum(a) / len(a) < 10.5
    assert {p.values["b"] for p in pts} == {"x", "y"}


def test_set_key_replaces_list_items_and_nested_keys():
    doc = {"follower": {"base": {"position": [1, 2, 3]}}, "solver": {"name": "x"}}
    set_key(doc, "follower.base.position.1", 20, spec_path="s.yaml")
    set_key(doc, "solver.options.eps", 1e-6, spec_path="s.yaml")
    assert doc["follower"]["base"]["position"] == [1, 20, 3]
    assert doc["solver"] == {"name": "x", "options": {"eps": 1e-6}}
    with pytest.raises(ConfigError, match="index 5 is out of range") as err:
        set_key(doc, "follower.base.position.5", 0, spec_path="s.yaml")
    assert err.value.key == "follower.base.position.5" and err.value.path == "s.yaml"
    with pytest.raises(ConfigError, match="not a mapping or a list"):
        set_key(doc, "solver.name.x", 0, spec_path="s.yaml")


def test_point_key_follows_content_and_code(tmp_path):
    spec = load_sweep(write_sweep(tmp_path))
    base = yaml.safe_load(BASE.read_text())
    p0, p1 = expand(spec)[:2]
    d0 = point_document(base, spec, p0)
    assert point_key(d0, 1, "c") == point_key(point_document(base, spec, p0), 1, "c")
    assert point_key(d0, 1, "c") != point_key(point_document(base, spec, p1), 1, "c")
    assert point_key(d0, 1, "c") != point_key(d0, 2, "c")
    assert point_key(d0, 1, "c") != point_key(d0, 1, "other code")


def test_an_unreachable_start_is_a_result_not_bad_input(tmp_path):
    spec = load_sweep(write_sweep(tmp_path))
    tasks = prepare_points(spec, "code")
    unreachable = {(t.values["follower.base.position.0"], t.values["follower.base.position.1"])
                   for t in tasks if t.start_failure}
    assert (0, 1000) in unreachable and (300, 1380) not in unreachable
    bad = write_sweep(tmp_path, "nowhere", grid={"follower.base.position.0": [5000, 6000]})
    with pytest.raises(ConfigError, match="no point can start"):
        prepare_points(load_sweep(bad), "code")


def _exit_and_error(capsys, path, out):
    code = main(["sweep", str(path), "--out", str(out), "--quiet"])
    return code, capsys.readouterr().err


@pytest.mark.parametrize(("extra", "grid", "named", "says"), [
    ({"grids": {}}, None, "grids", "valid: name, description, base, set, grid"),
    ({}, {"follower.bse.position.0": [1, 2]}, "follower.bse", "unknown key"),
    ({}, {"solver.name": ["nullspace", "qp:nope"]}, "solver.name", "unknown solver 'qp:nope'"),
    ({}, {"controller.dt": [0.031, "fast"]}, "controller.dt", "not text"),
    ({}, {"follower.base.position.7": [1]}, "follower.base.position.7", "out of range"),
    ({}, {"solver.policy": ["scale"]}, "solver.policy", "unknown key"),
    ({"random": {"n": 3, "controller.dt": {"uniform": [0, 1]}}}, None, "random.seed",
     "missing 'seed'"),
    ({"random": {"n": 3, "seed": 1, "controller.dt": {"beta": [0, 1]}}}, None,
     "controller.dt", "valid: uniform, normal, choice"),
    ({"repeat": 0}, None, "repeat", ">= 1"),
    ({"paired": {"controller.dt": {"controller.duration": [1, 2]}}}, None,
     "paired.controller.dt", "valid: follower.base.position.0, follower.base.position.1"),
    ({"paired": {"follower.base.position.1": {"controller.duration": [1, 2, 3]}}}, None,
     "paired.follower.base.position.1.controller.duration", "needs a list of 2 values"),
    ({"paired": {"follower.base.position.1": {"controller.duration": [1, 2]}},
      "set": {"controller.duration": 1}}, None, "controller.duration", "both set and swept"),
    ({"labels": {"follower.base.position.2": "z"}}, None, "labels.follower.base.position.2",
     "is not a swept key (valid: follower.base.position.0, follower.base.position.1)"),
    ({"labels": {"follower.base.position.0": 5}}, None, "labels.follower.base.position.0",
     "must be non-empty text"),
    ({"labels": ["x"]}, None, "labels", "must be a mapping"),
])
def test_bad_sweep_files_exit_2_naming_file_and_key(tmp_path, capsys, extra, grid, named,
                                                     says):
    path = write_sweep(tmp_path, grid=grid, extra=extra)
    out = tmp_path / "out"
    code, err = _exit_and_error(capsys, path, out)
    assert code == 2, err
    assert str(path) in err and f"key '{named}" in err and says in err, err
    assert "Traceback" not in err
    assert not out.exists()  # nothing ran, and no empty folder is left


def test_repeat_and_the_rollouts_of_a_sweep_are_capped_naming_the_cap():
    doc = {"base": "b.yaml", "grid": {"a": [1, 2]}}
    with pytest.raises(ConfigError, match="is 1,000,000,000; at most 1,000") as err:
        parse_sweep({**doc, "repeat": 1_000_000_000}, "s.yaml")
    assert (err.value.path, err.value.key) == ("s.yaml", "repeat")
    random = {"n": 2000, "seed": 1, "c": {"uniform": [0, 1]}}  # 4,000 points
    with pytest.raises(ConfigError, match=r"4,000 points x 300 rollouts .* at most "
                       r"1,000,000") as err:
        parse_sweep({**doc, "random": random, "repeat": 300}, "s.yaml")
    assert err.value.key == "repeat"
    assert parse_sweep({**doc, "random": random, "repeat": 250}, "s.yaml").repeat == 250


def test_a_missing_base_file_names_the_sweep_file_the_key_and_the_path(tmp_path, capsys):
    path = write_sweep(tmp_path, extra={"base": "missing.yaml"})
    code, err = _exit_and_error(capsys, path, tmp_path / "out")
    assert code == 2, err
    assert f"{path}: key 'base': file not found: {tmp_path / 'missing.yaml'}" in err, err


@pytest.mark.parametrize(("content", "says"), [(None, "URDF file not found"),
                                                ("not a URDF", "cannot read URDF")])
def test_a_bad_file_in_the_grid_names_the_sweep_file_the_key_and_the_file(tmp_path, capfd,
                                                                         content, says):
    urdf = tmp_path / "arm.urdf"
    if content is not None:
        urdf.write_text(content)
    follower = {"urdf": {"file": "placeholder.urdf", "root": "base_link", "tip": "tool0"},
                "base": {"position": [300, 1380, 0]}, "initial": {"near": NEAR}}
    path = write_sweep(tmp_path, grid={"follower.urdf.file": [str(urdf)]},
                       extra={"set": {"controller.duration": 0.5, "follower": follower}})
    code = main(["sweep", str(path), "--out", str(tmp_path / "out"), "--quiet"])
    err = capfd.readouterr().err  # file descriptor 2: what C++ code prints too
    assert code == 2, err
    assert len(err.splitlines()) == 1, err  # our message only, no parser lines before it
    assert err.startswith(f"dualarm-qp: error: {path}: key 'follower.urdf.file': ")
    assert f"{says}" in err and str(urdf) in err


def test_a_folder_holding_other_files_is_refused(tmp_path, capsys):
    out = tmp_path / "out"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    code, err = _exit_and_error(capsys, write_sweep(tmp_path), out)
    assert code == 2 and "holds other files" in err
