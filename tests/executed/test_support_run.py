"""The paper's Case 2 on the PUMA beam (configs/puma_beam_support.yaml), checked from its outputs.

The run must complete. Its statics are then checked from trajectory.csv alone with a
force balance written here: the object's orientation from the leader's joints by the
independent PUMA forward kinematics (oracle.py), gravity in object coordinates, the
contact point from the CSV's grasp coordinate, and Eqs. 7-8 solved for the leader's
force and the follower's push by least squares. Bad files exit with code 2 and name
the key.
"""

from __future__ import annotations

import copy
import csv
import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from csv_check import check_valid, read_trajectory
from oracle import inv_pose, puma_fk

from dualarm_qp.cli import main

CONFIG = Path(__file__).resolve().parents[2] / "configs" / "puma_beam_support.yaml"


def _cli(cfg: Path, out: Path) -> int:
    """``dualarm-qp run`` in this process; its exit code."""
    return main(["run", str(cfg), "--out", str(out), "--no-plots", "--quiet"])


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("support") / "out"
    assert _cli(CONFIG, out) == 0
    return out


@pytest.fixture(scope="module")
def run(run_dir: Path) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    summary = json.loads((run_dir / "summary.json").read_text())
    return read_trajectory(run_dir / "trajectory.csv"), summary


#: The run as recorded before the hand wrenches were added (data/, see its "about").
BEFORE = json.loads((Path(__file__).parent / "data" / "support_run_before_loads.json")
                    .read_text())
LOAD_COLUMNS = [f"f_{role}_{part}" for role in ("leader", "follower")
                for part in ("fx", "fy", "fz", "mx", "my", "mz")]


def test_support_output_is_unchanged_by_the_hand_wrenches(run_dir: Path) -> None:
    """Every earlier column and summary entry as before; only the wrench and torque
    columns, summary ``loads`` and ``realised_limits.torque`` are new. The record was
    made with the Python-era exact solver: the compiled one agrees with it to 1e-12 per
    step (its null-space basis comes from another SVD), hence the tolerances."""
    with open(run_dir / "trajectory.csv", newline="") as fh:
        rows = list(csv.reader(fh))
    header = rows[0]
    # Joint torques were added after the wrenches (a task with a load records them).
    torques = [f"tau_{role}_{i}" for role in ("leader", "follower") for i in range(1, 7)]
    assert header == BEFORE["header"] + LOAD_COLUMNS + torques
    assert len(rows) - 1 == BEFORE["samples"]
    for name, values in BEFORE["columns"].items():
        now = [rows[1 + k][header.index(name)] for k in BEFORE["rows"]]
        try:
            np.testing.assert_allclose(np.array(now, dtype=float),
                                       np.array(values, dtype=float), rtol=1e-9, atol=1e-12,
                                       err_msg=name)
        except ValueError:  # a text column
            assert now == values, name
    summary = json.loads((run_dir / "summary.json").read_text())
    assert set(summary) - set(BEFORE["summary"]) >= {"loads"}
    summary["realised_limits"].pop("torque")  # added with the joint torques
    for part in summary["realised_limits"].values():  # added with the jerk limits
        for key in ("jerk_ratio_max", "worst_jerk"):
            part.pop(key, None)
    for key, value in BEFORE["summary"].items():
        assert_close(summary[key], value, key)


def assert_close(now: Any, before: Any, where: str) -> None:
    """``now`` equals ``before``: the same keys and texts, numbers to 1e-9 (nested)."""
    if isinstance(before, dict):
        assert isinstance(now, dict) and set(now) == set(before), where
        for key, value in before.items():
            assert_close(now[key], value, f"{where}.{key}")
    elif isinstance(before, list):
        assert isinstance(now, list) and len(now) == len(before), where
        for i, (a, b) in enumerate(zip(now, before, strict=True)):
            assert_close(a, b, f"{where}[{i}]")
    elif isinstance(before, float) and not isinstance(now, bool):
        assert now == pytest.approx(before, rel=1e-9, abs=1e-12, nan_ok=True), where
    else:
        assert now == before, where


def test_support_wrenches_are_the_push_and_the_leader_takes_the_rest(
        run: tuple[dict[str, np.ndarray], dict[str, Any]]) -> None:
    """The follower's wrench is the recorded push along the face normal, no moment; the
    leader's balances the whole weight (its moments included), from the CSV alone."""
    traj, summary = run
    spec = yaml.safe_load(CONFIG.read_text())["object"]
    mass = float(spec["mass"])
    r_c = np.array(spec["mass_centre"], dtype=float) / 1000.0
    g_world = np.array(spec["gravity"], dtype=float) / 1000.0
    q_l = np.column_stack([traj[f"ql{i}"] for i in range(1, 7)])
    w_l = np.column_stack([traj[c] for c in LOAD_COLUMNS[:6]])
    w_f = np.column_stack([traj[c] for c in LOAD_COLUMNS[6:]])
    worst = 0.0
    for k in range(len(traj["t"])):
        T_obj = puma_fk(q_l[k])
        a = T_obj[:3, 0]                                    # the face normal: object x
        np.testing.assert_allclose(w_f[k], np.r_[traj["support_force"][k] * a, 0, 0, 0],
                                   rtol=0, atol=1e-9 * mass * 9.81)
        p1, p2 = T_obj[:3, 3], (T_obj @ [0.0, 0.0, traj["grasp"][k], 1.0])[:3]
        centre = (T_obj @ np.r_[r_c, 1.0])[:3]
        weight = mass * g_world
        force = w_l[k, :3] + w_f[k, :3] + weight
        moment = (w_l[k, 3:] + w_f[k, 3:] + np.cross(p2 - p1, w_f[k, :3])
                  + np.cross(centre - p1, weight))
        worst = max(worst, float(np.abs(np.r_[force, moment]).max()))
    assert worst < 1e-9 * mass * 9.81
    assert summary["loads"]["internal_dimensions"] == 0
    # With gravity along object x (the beam does not turn) the leader needs no moment:
    # the paper's assumption (a), which the support line is built to satisfy.
    assert np.abs(w_l[:, 3:]).max() < 1e-3  # [N m]; gravity off x is below 3e-5 m/s^2


def test_support_config_runs_and_completes(run: tuple[dict[str, np.ndarray], dict[str, Any]]
                                           ) -> None:
    traj, summary = run
    assert summary["completed"], summary["message"]
    assert summary["solver"] == "nullspace"
    assert summary["path_completed_pct"] == pytest.approx(100.0)
    assert not check_valid(traj)
    assert len(traj["support_force"]) == summary["samples"] == 501


def _skew(v: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def test_support_statics_from_the_csv(run: tuple[dict[str, np.ndarray], dict[str, Any]]
                                      ) -> None:
    """Eqs. 7-8 about the object origin hold with h > 0 at every recorded sample."""
    traj, summary = run
    spec = yaml.safe_load(CONFIG.read_text())["object"]
    mass = float(spec["mass"])                                   # kg
    r_c = np.array(spec["mass_centre"], dtype=float) / 1000.0   # mm -> m
    g_world = np.array(spec["gravity"], dtype=float) / 1000.0   # mm/s^2 -> m/s^2
    assert spec["H1"] == {"position": [0, 0, 0]}  # object frame = leader's hand frame
    r1 = np.zeros(3)        # the leader's hand origin in object coordinates
    a = np.array([1.0, 0.0, 0.0])  # the face x = 0; the follower pushes along +x
    # The beam's support line: the plane x = 0 through the leader's hand (origin) and
    # the mass centre (on the z axis) is the z axis; the grasp coordinate is z.
    assert r_c[0] == r_c[1] == 0.0

    q_l = np.column_stack([traj[f"ql{i}"] for i in range(1, 7)])
    q_f = np.column_stack([traj[f"qf{i}"] for i in range(1, 7)])
    base_f = np.eye(4)
    base_f[:3, :3] = summary["reconstruction"]["follower_base_rotation"]
    base_f[:3, 3] = summary["reconstruction"]["follower_base_m"]
    h_all, residuals, neglected, hand_gap = [], [], [], []
    for k in range(len(traj["t"])):
        T_obj = puma_fk(q_l[k])                 # world <- object (H1 = identity)
        g = T_obj[:3, :3].T @ g_world           # gravity in object coordinates
        g_t = np.array([g[0], 0.0, 0.0])        # the part a normal push balances (Eq. 8)
        r2 = np.array([0.0, 0.0, traj["grasp"][k]])
        # Unknowns x = [f_l (3), h]: r1 x f_l + r2 x h a + r_c x M g~ = 0,
        # f_l + h a + M g~ = 0.
        A = np.zeros((6, 4))
        A[:3, :3] = _skew(r1)
        A[:3, 3] = np.cross(r2, a)
        A[3:, :3] = np.eye(3)
        A[3:, 3] = a
        b = np.concatenate([-np.cross(r_c, mass * g_t), -mass * g_t])
        x = np.linalg.lstsq(A, b, rcond=None)[0]
        residuals.append(float(np.max(np.abs(A @ x - b))))
        h_all.append(float(x[3]))
        neglected.append(float(np.hypot(g[1], g[2])))
        # The follower's hand is where the CSV says it pushes.
        p_hand = (inv_pose(T_obj) @ puma_fk(q_f[k], base=base_f))[:3, 3]
        hand_gap.append(float(np.linalg.norm(p_hand - r2)))
    h = np.array(h_all)
    assert max(residuals) < 1e-9          # [N m, N]: an exact balance
    assert h.min() > 0.0                  # the follower only pushes
    np.testing.assert_allclose(traj["support_force"], h, rtol=1e-9)
    # The parts of gravity the model hands to the leader stay negligible: the beam
    # does not turn (x_o stays up).
    assert max(neglected) < 1e-3 * np.linalg.norm(g_world)
    assert max(hand_gap) < 1e-4  # [m]
    # The push: M g r_cz / z, from 0.556 M g at the start (450 mm) upwards.
    assert h[0] == pytest.approx(mass * 9.81 * 0.25 / 0.45, rel=1e-6)


def _bad(data: dict[str, Any], path: Path) -> Path:
    path.write_text(yaml.safe_dump(data))
    return path


def _with(edit: dict[str, Any], drop: tuple[str, ...] = ()) -> dict[str, Any]:
    data = yaml.safe_load(CONFIG.read_text())
    obj = copy.deepcopy(data["object"])
    obj.update(edit)
    for key in drop:
        obj.pop(key)
    data["object"] = obj
    return data


BAD = {
    "no_mass": (_with({}, drop=("mass",)), "object.mass"),
    "zero_mass": (_with({"mass": 0}), "object.mass"),
    "unknown_contact": (_with({"contact": "glue"}), "object.contact"),
    "negative_mass": (_with({"mass": -4}), "object.mass"),
    "centre_without_mass": (_with({"contact": "grasp"}, drop=("mass",)), "object.mass_centre"),
    "centre_two_numbers": (_with({"mass_centre": [0, 250]}), "object.mass_centre"),
    "curved_surface": (_with({"surface": {"type": "curved_bar", "radius": 800,
                                          "grasp_range": [-200, 200]}}),
                       "object.surface.type"),
    "zero_gravity": (_with({"gravity": [0, 0, 0]}), "object.gravity"),
    "gravity_across": (_with({"gravity": [9810, 0, 0]}), "object.gravity"),
    "gravity_up": (_with({"gravity": [0, 0, 9810]}), "object.mass_centre"),
    "centre_off_bar": (_with({"mass_centre": [0, 30, 250]}), "object.mass_centre"),
    "start_needs_pull": (_with({"grasp_initial": -20}), "object.grasp_initial"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_support_configs_exit_2_naming_the_key(case: str, tmp_path: Path,
                                                   capsys: pytest.CaptureFixture[str]) -> None:
    data, key = BAD[case]
    code = _cli(_bad(data, tmp_path / f"{case}.yaml"), tmp_path / "out")
    err = capsys.readouterr().err
    assert code == 2, err
    assert f"'{key}'" in err, err


def test_a_step_that_would_need_a_pull_fails_on_criterion_support():
    """A grasp far behind the leader's hand needs a pull: the step says so, the run fails
    on its own criterion."""
    import dataclasses

    from dualarm_qp.control.rollout import CRITERIA, rollout
    from dualarm_qp.errors import SupportLostError
    from dualarm_qp.experiments import build_experiment, load_config

    assert "support" in CRITERIA
    exp = build_experiment(load_config(CONFIG), str(CONFIG))
    exp.controller().step(exp.initial)  # the shipped start is supported
    bad = dataclasses.replace(exp.initial, sigma=-10.0)
    with pytest.raises(SupportLostError, match="support lost"):
        exp.controller().step(bad)
    res = rollout(exp.controller(), bad, duration=0.1)
    assert res.failure is not None and res.failure.criterion == "support", res.message
