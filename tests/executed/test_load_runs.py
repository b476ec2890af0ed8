"""The hand wrenches of real runs, recomputed here from the CSV joints alone.

configs/puma_beam_limits.yaml and configs/ur5_pair_sliding_bar.yaml (shortened to 1 s)
are run with a mass added. From trajectory.csv: the object's pose by the independent
forward kinematics (oracle.py, urdf_oracle.py) and ``H1``, the grasp points (the leader's
tool point, the follower's contact point ``[0, 0, grasp]`` on the bar), and then, with
the statics oracle: the recorded wrenches balance the weight, the sliding grasp carries
no force along the bar and no moment about it, and they are the minimum-norm split.
"""

from __future__ import annotations

import copy
import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from csv_check import read_trajectory
from oracle import puma_fk
from statics_oracle import min_norm_split, residual, slide_space
from urdf_oracle import UrdfChain, config_pose

from dualarm_qp.cli import main
from dualarm_qp.kinematics.robots import example_robot_urdf, example_robots_dir

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
PARTS = ("fx", "fy", "fz", "mx", "my", "mz")
MASS = {"puma_beam_limits": (3.0, [0.0, 0.0, 250.0]),
        "ur5_pair_sliding_bar": (2.0, [0.0, 0.0, 350.0])}


def _data(name: str) -> dict[str, Any]:
    data = yaml.safe_load((CONFIGS / f"{name}.yaml").read_text())
    mass, centre = MASS[name]
    data["object"].update(mass=mass, mass_centre=centre)
    if name.startswith("ur5"):
        data["controller"]["duration"] = 1.0
    return data


def _run(name: str, tmp: Path) -> tuple[dict[str, np.ndarray], dict[str, Any], dict[str, Any]]:
    data = _data(name)
    cfg = tmp / f"{name}.yaml"
    cfg.write_text(yaml.safe_dump(data))
    out = tmp / "out"
    assert main(["run", str(cfg), "--out", str(out), "--no-plots", "--quiet"]) == 0
    return (read_trajectory(out / "trajectory.csv"),
            json.loads((out / "summary.json").read_text()), data)


@pytest.fixture(scope="module", params=sorted(MASS))
def run(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory
        ) -> tuple[str, dict[str, np.ndarray], dict[str, Any], dict[str, Any]]:
    name = request.param
    if name.startswith("ur5") and example_robots_dir() is None:
        pytest.skip("example-robot-data is not installed")
    return (name, *_run(name, tmp_path_factory.mktemp(name)))


def _leader_tool(name: str, data: dict[str, Any]):
    if name.startswith("puma"):
        return puma_fk
    model = data["leader"]["example_robot"]
    chain = UrdfChain(example_robot_urdf(model["name"]), model["root"], model["tip"])
    base = config_pose(data["leader"]["base"])
    return lambda q: chain.fk(q, base, np.eye(4))


def test_loads_recomputed_from_the_csv_joints(run) -> None:
    name, traj, summary, data = run
    assert summary["completed"], summary["message"]
    mass = data["object"]["mass"]
    r_c = np.array(data["object"]["mass_centre"]) / 1000.0
    weight = mass * np.array([0.0, 0.0, -9.81])  # the default gravity
    H1 = config_pose(data["object"]["H1"])
    fk = _leader_tool(name, data)
    q_l = np.column_stack([traj[f"ql{i}"] for i in range(1, 7)])
    w_l = np.column_stack([traj[f"f_leader_{p}"] for p in PARTS])
    w_f = np.column_stack([traj[f"f_follower_{p}"] for p in PARTS])
    worst = {"balance": 0.0, "slide": 0.0, "split": 0.0}
    for k in range(len(traj["t"])):
        T_tool = fk(q_l[k])
        T_obj = T_tool @ H1
        p1 = T_tool[:3, 3]
        p2 = (T_obj @ [0.0, 0.0, traj["grasp"][k], 1.0])[:3]
        s = T_obj[:3, 2]                                # the bar's axis: object z
        centre = (T_obj @ np.r_[r_c, 1.0])[:3]
        about = np.array([0.3, -0.2, 0.1])              # any common point
        res = residual([p1, p2], np.array([w_l[k], w_f[k]]), centre, weight, about)
        worst["balance"] = max(worst["balance"], float(np.abs(res).max()))
        worst["slide"] = max(worst["slide"], abs(w_f[k, :3] @ s), abs(w_f[k, 3:] @ s))
        L = float(np.linalg.norm(p2 - p1))
        best = min_norm_split([p1, p2], [np.eye(6), slide_space(s)], centre, weight, L)
        worst["split"] = max(worst["split"], float(np.abs(best - [w_l[k], w_f[k]]).max()))
    scale = mass * 9.81
    assert worst["balance"] < 1e-9 * scale, worst   # [N, N m]
    assert worst["slide"] < 1e-9 * scale, worst      # frictionless, and free to spin
    assert worst["split"] < 1e-9 * scale, worst      # the minimum-norm split
    # The follower really carries part of the load (not all on the leader).
    assert np.linalg.norm(w_f[:, :3], axis=1).min() > 0.1 * scale


def test_summary_loads_are_the_csv_peaks(run) -> None:
    _, traj, summary, data = run
    loads = summary["loads"]
    assert loads["mass_kg"] == data["object"]["mass"]
    assert loads["unbalanced_samples"] == 0
    assert loads["internal_dimensions"] == 4
    for role in ("leader", "follower"):
        w = np.column_stack([traj[f"f_{role}_{p}"] for p in PARTS])
        f, m = np.linalg.norm(w[:, :3], axis=1), np.linalg.norm(w[:, 3:], axis=1)
        assert loads[role]["force_max_N"] == pytest.approx(f.max(), rel=1e-12)
        assert loads[role]["moment_max_N_m"] == pytest.approx(m.max(), rel=1e-12)
        assert loads[role]["force_max_sample"] == int(np.argmax(f))


def test_without_a_mass_no_force_columns(tmp_path: Path) -> None:
    data = copy.deepcopy(_data("puma_beam_limits"))
    for key in ("mass", "mass_centre"):
        data["object"].pop(key)
    data["controller"]["duration"] = 0.31
    cfg = tmp_path / "no_mass.yaml"
    cfg.write_text(yaml.safe_dump(data))
    assert main(["run", str(cfg), "--out", str(tmp_path / "out"), "--no-plots",
                 "--quiet"]) == 0
    header = (tmp_path / "out" / "trajectory.csv").read_text().splitlines()[0].split(",")
    assert not [h for h in header if h.startswith(("f_leader_", "f_follower_"))]
    assert "loads" not in json.loads((tmp_path / "out" / "summary.json").read_text())


def _both_sliding(edit: dict[str, Any]) -> dict[str, Any]:
    data = yaml.safe_load((CONFIGS / "both_sliding_bar.yaml").read_text())
    data["object"].update(edit)
    return data


BAD = {
    "negative_mass": (lambda: _edit({"mass": -3}), "object.mass"),
    "centre_two_numbers": (lambda: _edit({"mass_centre": [0, 250]}), "object.mass_centre"),
    "centre_four_numbers": (lambda: _edit({"mass_centre": [0, 0, 250, 1]}),
                            "object.mass_centre"),
    "zero_gravity": (lambda: _edit({"gravity": [0, 0, 0]}), "object.gravity"),
    "gravity_without_mass": (lambda: _edit({"gravity": [0, 0, -9810]},
                                           drop=("mass", "mass_centre")),
                             "object.gravity"),
    # Both grasps slide along the bar: a load along it, or turning it about its axis, is
    # held by neither.
    "gravity_along_both_slides": (lambda: _both_sliding(
        {"mass": 2, "mass_centre": [0, 0, 300], "gravity": [9810, 0, 0]}), "object.gravity"),
    "centre_off_both_slides": (lambda: _both_sliding(
        {"mass": 2, "mass_centre": [0, 50, 300]}), "object.mass_centre"),
}


def _edit(edit: dict[str, Any], drop: tuple[str, ...] = ()) -> dict[str, Any]:
    data = _data("puma_beam_limits")
    data["object"].update(edit)
    for key in drop:
        data["object"].pop(key)
    return data


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_loads_exit_2_naming_the_key(case: str, tmp_path: Path,
                                         capsys: pytest.CaptureFixture[str]) -> None:
    make, key = BAD[case]
    if "both_slides" in case and example_robots_dir() is None:
        pytest.skip("example-robot-data is not installed")
    cfg = tmp_path / f"{case}.yaml"
    cfg.write_text(yaml.safe_dump(make()))
    code = main(["run", str(cfg), "--out", str(tmp_path / "out"), "--no-plots", "--quiet"])
    err = capsys.readouterr().err
    assert code == 2, err
    assert f"'{key}'" in err, err
    assert not (tmp_path / "out").exists()


def test_both_slides_across_the_bar_hold_the_load(tmp_path: Path) -> None:
    """The shipped both-sliding bar with a mass on its axis: every sample balanced."""
    if example_robots_dir() is None:
        pytest.skip("example-robot-data is not installed")
    data = _both_sliding({"mass": 2, "mass_centre": [0, 0, 400]})
    data["controller"]["duration"] = 0.5
    cfg = tmp_path / "both.yaml"
    cfg.write_text(yaml.safe_dump(data))
    assert main(["run", str(cfg), "--out", str(tmp_path / "out"), "--no-plots",
                 "--quiet"]) == 0
    loads = json.loads((tmp_path / "out" / "summary.json").read_text())["loads"]
    traj = read_trajectory(tmp_path / "out" / "trajectory.csv")
    # 4 + 4 wrench dimensions, of which the balance uses 4 (the axes coincide): the
    # other 4 are internal.
    assert loads["unbalanced_samples"] == 0 and loads["internal_dimensions"] == 4
    axis = np.array([1.0, 0.0, 0.0])  # the bar lies along world x (object z) and stays so
    for role in ("leader", "follower"):  # nothing along the bar, no moment about it
        w = np.column_stack([traj[f"f_{role}_{p}"] for p in PARTS])
        assert np.abs(w[:, :3] @ axis).max() < 1e-9 * 19.62
        assert np.abs(w[:, 3:] @ axis).max() < 1e-9 * 19.62
    weight = np.array([0.0, 0.0, -2 * 9.81])
    total = sum(np.column_stack([traj[f"f_{r}_{p}"] for p in ("fx", "fy", "fz")])
                for r in ("leader", "follower"))
    np.testing.assert_allclose(total, np.broadcast_to(-weight, total.shape), atol=1e-9 * 19.62)


def test_samples_the_grasps_cannot_hold_are_nan_and_warned() -> None:
    """A task built in Python (no start check) whose load the two slides cannot hold."""
    if example_robots_dir() is None:
        pytest.skip("example-robot-data is not installed")
    import dataclasses

    from dualarm_qp.control.rollout import rollout
    from dualarm_qp.experiments import build_experiment, parse_config
    from dualarm_qp.task.loads import ObjectLoad

    exp = build_experiment(parse_config(_both_sliding({"mass": 2})), "both_sliding_bar")
    assert exp.task.load is not None
    along = ObjectLoad(2.0, [0.0, 0.0, 0.3], [9.81, 0.0, 0.0])  # world x: along the bar
    exp = dataclasses.replace(exp, task=dataclasses.replace(exp.task, load=along))
    res = rollout(exp.controller(), exp.initial, duration=0.03)
    n = len(res.trace)
    assert n > 1
    assert np.isnan(res.trace.f_leader).all() and np.isnan(res.trace.f_follower).all()
    assert res.extras["loads"]["unbalanced_samples"] == n
    assert any("cannot hold the load" in w for w in res.warnings)
