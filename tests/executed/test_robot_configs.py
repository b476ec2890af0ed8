"""The shipped robot configs run, complete, and their RECORDED motion keeps every rule.

Each config in ``ROBOT_CONFIGS`` is run once through the command line (in-process) with
its own hard-limit solver. Its ``trajectory.csv`` is then checked independently of
``summary.json`` and of the library's kinematics:

* the limits come from the URDF's ``limit`` tags (read as XML) overridden by the YAML's
  ``q_min`` / ``q_max`` / ``qd_max``, and the grasp ranges from the YAML's ``plane_bar``
  boxes: every speed (finite differences) and range is kept;
* forward kinematics comes from :mod:`urdf_oracle` (the URDF's joint origins and axes
  chained with numpy), the bases, ``H1`` and the path D(t) from the YAML: the leader
  puts the object on D(path_t) and the follower closes the grasp, within the run's
  tolerances (1 mm, 0.01 rad), on every row;
* every joint frame of both arms stays above the plane of the robots' bases (no arm
  through the table), the grasps slide, and each config does what its header says.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from csv_check import (
    Limits,
    check_accelerations,
    check_path_complete,
    check_ranges,
    check_speeds,
    check_valid,
    joint_columns,
    read_trajectory,
)
from urdf_oracle import (
    UrdfChain,
    axis_rotation,
    homogeneous,
    plane_bar_pose,
    rotation_angle,
    rpy_matrix,
)

from dualarm_qp.cli import main
from dualarm_qp.kinematics.robots import example_robot_urdf, example_robots_dir

pytestmark = pytest.mark.skipif(
    example_robots_dir() is None,
    reason="example-robot-data is not installed (pip install -e '.[robots]'; '.[dev]' has it)")

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
ROBOT_CONFIGS = ("ur5_pair_sliding_bar", "panda_pair", "baxter_tray", "both_sliding_bar",
                 "panda_pair_accel", "kinova_pair", "ur10_panda_pair")
#: Configs with collision avoidance (their clearance: test_collision_configs.py); their
#: runs take a few seconds each, so they are checked in the slow loop.
COLLISION_CONFIGS = ("ur5_pair_collision", "panda_pair_shelf")
CASES = [*ROBOT_CONFIGS, *(pytest.param(n, marks=pytest.mark.slow) for n in COLLISION_CONFIGS)]
#: The runs' tracking and closure tolerances (the configs keep the defaults).
POSITION_TOL, ANGLE_TOL = 1e-3, 1e-2
LENGTH = {"m": 1.0, "mm": 1e-3}
ANGLE = {"rad": 1.0, "deg": math.pi / 180.0}


# ------------------------------------------------------------------ the YAML, read here
class Spec:
    """The parts of a config file the checks need, in SI units, read without the library."""

    def __init__(self, data: dict[str, Any]) -> None:
        units = data.get("units", {})
        assert units.get("time", "s") == "s"
        self.length = LENGTH[units.get("length", "m")]
        self.angle = ANGLE[units.get("angle", "rad")]
        self.data = data
        c = data["controller"]
        self.dt = float(c["dt"])
        self.duration = float(c["duration"])
        self.grasp_speed = float(c["grasp_speed_max"]) * self.length
        self.acceleration_limits = bool(c.get("acceleration_limits", False))
        self.grasp_acc = float(c.get("grasp_acc_max", math.inf)) * self.length
        assert c.get("initial_rates", "rest") == "rest"  # the checks start from rest

    def joint_accelerations(self, role: str, n: int) -> np.ndarray:
        """The YAML's ``qdd_max`` [rad/s^2] (a URDF states none: with acceleration
        limits on, the file must state them)."""
        arm = self.data[role]
        if "qdd_max" not in arm:
            assert not self.acceleration_limits, f"{role}.qdd_max"
            return np.full(n, np.inf)
        return np.array(arm["qdd_max"], dtype=float) * self.angle

    def pose(self, spec: dict[str, Any] | None) -> np.ndarray:
        if spec is None:
            return np.eye(4)
        if "rotation" in spec:
            R = np.array(spec["rotation"], dtype=float)
        else:
            R = rpy_matrix(*(v * self.angle for v in spec.get("rpy", [0, 0, 0])))
        return homogeneous(R, np.array(spec["position"], dtype=float) * self.length)

    def chain(self, role: str) -> UrdfChain:
        model = self.data[role]["example_robot"]
        return UrdfChain(example_robot_urdf(model["name"]), model["root"], model["tip"])

    def base(self, role: str) -> np.ndarray:
        return self.pose(self.data[role]["base"])

    def tool(self, role: str) -> np.ndarray:
        return self.pose(self.data[role].get("tool"))

    def joint_limits(self, role: str, chain: UrdfChain) -> tuple[np.ndarray, ...]:
        """The URDF's ranges and speeds, overridden by the YAML's (a URDF speed 0: none)."""
        arm = self.data[role]
        lo = np.array([j.lower for j in chain.moving])
        hi = np.array([j.upper for j in chain.moving])
        vel = np.array([j.velocity if j.velocity > 0 else np.inf for j in chain.moving])
        for key, values, scale in (("q_min", lo, self.angle), ("q_max", hi, self.angle),
                                   ("qd_max", vel, self.angle)):
            if key in arm:
                values[:] = np.array(arm[key], dtype=float) * scale
        return lo, hi, vel

    def grasp_range(self, key: str) -> tuple[float, float]:
        """A ``plane_bar``'s range along object z: its box's z bounds."""
        surface = self.data["object"][key]
        assert surface["type"] == "plane_bar" and set(surface) == {"type", "r_min", "r_max"}
        assert surface["r_min"][:2] == [0, 0] and surface["r_max"][:2] == [0, 0]
        return surface["r_min"][2] * self.length, surface["r_max"][2] * self.length

    @property
    def leader_slides(self) -> bool:
        return "leader_surface" in self.data["object"]

    def H1(self) -> np.ndarray:
        return self.pose(self.data["object"].get("H1"))

    def path(self, t: float) -> np.ndarray:
        """D(t): linear, or through waypoints with minimum-jerk timing and rotation
        along the geodesic ``R_k exp(s log(R_k^T R_k+1))``."""
        tr = self.data["trajectory"]
        if tr["type"] == "linear":
            T = self.pose(tr["start"])
            T[:3, 3] += np.array(tr["velocity"], dtype=float) * self.length * t
            return T
        points = tr["waypoints"]
        times = [float(w["t"]) for w in points]
        if t >= times[-1]:
            return self.pose(points[-1]["pose"])
        k = max(i for i in range(len(times) - 1) if times[i] <= t)
        tau = (t - times[k]) / (times[k + 1] - times[k])
        s = 10 * tau**3 - 15 * tau**4 + 6 * tau**5
        A, B = self.pose(points[k]["pose"]), self.pose(points[k + 1]["pose"])
        R_rel = A[:3, :3].T @ B[:3, :3]
        angle = rotation_angle(R_rel)
        R = A[:3, :3]
        if angle > 1e-12:
            axis = np.array([R_rel[2, 1] - R_rel[1, 2], R_rel[0, 2] - R_rel[2, 0],
                             R_rel[1, 0] - R_rel[0, 1]]) / (2 * math.sin(angle))
            R = R @ axis_rotation(axis, s * angle)
        return homogeneous(R, A[:3, 3] + s * (B[:3, 3] - A[:3, 3]))


# ------------------------------------------------------------------ one run per config
@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """Run each config once (lazily) through ``dualarm-qp run``; cache the results."""
    cache: dict[str, Any] = {}

    def get(name: str) -> tuple[Spec, int, dict[str, Any], dict[str, np.ndarray]]:
        if name not in cache:
            out = tmp_path_factory.mktemp(name) / "run"
            code = main(["run", str(CONFIGS / f"{name}.yaml"), "--out", str(out),
                         "--no-plots", "--quiet"])
            summary = json.loads((out / "summary.json").read_text())
            spec = Spec(yaml.safe_load((CONFIGS / f"{name}.yaml").read_text()))
            cache[name] = (spec, code, summary, read_trajectory(out / "trajectory.csv"))
        return cache[name]

    return {"get": get}


def independent_limits(spec: Spec) -> Limits:
    bounds: dict[str, tuple[float, float]] = {}
    speeds: dict[str, float] = {}
    accels: dict[str, float] = {}
    for role, prefix in (("leader", "ql"), ("follower", "qf")):
        lo, hi, vel = spec.joint_limits(role, spec.chain(role))
        acc = spec.joint_accelerations(role, lo.size)
        for i in range(lo.size):
            bounds[f"{prefix}{i + 1}"] = (float(lo[i]), float(hi[i]))
            speeds[f"{prefix}{i + 1}"] = float(vel[i])
            accels[f"{prefix}{i + 1}"] = float(acc[i])
    bounds["grasp"] = spec.grasp_range("surface")
    speeds["grasp"] = spec.grasp_speed
    accels["grasp"] = spec.grasp_acc
    if spec.leader_slides:
        bounds["grasp_leader"] = spec.grasp_range("leader_surface")
        speeds["grasp_leader"] = spec.grasp_speed
        accels["grasp_leader"] = spec.grasp_acc
    return Limits(dt=spec.dt, t_end=spec.duration, speed_limits=True, bounds=bounds,
                  speeds=speeds, acceleration_limits=spec.acceleration_limits,
                  accelerations=accels, start_rates={c: 0.0 for c in accels})


def rows(traj: dict[str, np.ndarray], prefix: str) -> np.ndarray:
    return np.column_stack([traj[c] for c in joint_columns(traj, prefix)])


# ------------------------------------------------------------------ the tests
@pytest.mark.parametrize("name", CASES)
def test_config_completes_and_records_its_arms(name: str, runs: dict[str, Any]) -> None:
    spec, code, summary, traj = runs["get"](name)
    assert code == 0, summary.get("failure")
    assert summary["completed"] is True and summary["hard_limits"] is True
    assert summary["solver"] == "nullspace" and summary["policy"] == "scale"
    assert summary["settings"]["velocity_limits"] is True
    for role, prefix in (("leader", "ql"), ("follower", "qf")):
        model = spec.data[role]["example_robot"]
        chain = spec.chain(role)
        record = summary["arms"][role]
        assert record["source"] == (f"example_robot:{model['name']} "
                                    f"{model['root']}->{model['tip']}")
        assert record["joints"] == len(chain.moving) == len(joint_columns(traj, prefix))
        assert record["joint_names"] == chain.names


@pytest.mark.parametrize("name", CASES)
def test_recorded_motion_keeps_every_limit(name: str, runs: dict[str, Any]) -> None:
    spec, _, _, traj = runs["get"](name)
    assert not check_valid(traj)
    lim = independent_limits(spec)
    assert ("grasp_leader" in traj) == spec.leader_slides
    problems = (check_speeds(traj, lim) + check_accelerations(traj, lim)
                + check_ranges(traj, lim) + check_path_complete(traj, lim))
    assert not problems, "\n".join(problems)
    # Starting inside every range, the run stays inside (not just "never further out").
    for c, (lo, hi) in lim.bounds.items():
        assert lo - 1e-9 <= traj[c].min() and traj[c].max() <= hi + 1e-9, c


def geometry(spec: Spec, traj: dict[str, np.ndarray]) -> dict[str, float]:
    """From the CSV's joints and grasps, with the URDF oracle: the worst leader tracking
    (object against D(path_t)) and grasp closure errors [m, rad], the lowest joint frame
    [m] and the largest tilt of the object's x axis from the vertical [rad]."""
    chains = {role: spec.chain(role) for role in ("leader", "follower")}
    bases = {role: spec.base(role) for role in chains}
    tools = {role: spec.tool(role) for role in chains}
    q = {"leader": rows(traj, "ql"), "follower": rows(traj, "qf")}
    H1 = spec.H1()
    worst = {"track_p": 0.0, "track_r": 0.0, "close_p": 0.0, "close_r": 0.0,
             "lowest_z": math.inf, "tilt": 0.0}
    for k in range(len(traj["t"])):
        frames = {role: chains[role].frames(q[role][k], bases[role]) for role in chains}
        worst["lowest_z"] = min(worst["lowest_z"],
                                *(float(T[2, 3]) for f in frames.values() for T in f))
        T_l = frames["leader"][-1] @ tools["leader"]
        T_f = frames["follower"][-1] @ tools["follower"]
        if spec.leader_slides:  # the leader's grasp frame on the object is G_l(sigma_l)
            T_obj = T_l @ np.linalg.inv(plane_bar_pose(float(traj["grasp_leader"][k])))
        else:
            T_obj = T_l @ H1
        D = spec.path(float(traj["path_t"][k]))
        grasp = T_obj @ plane_bar_pose(float(traj["grasp"][k]))
        for key, A, B in (("track", T_obj, D), ("close", T_f, grasp)):
            worst[f"{key}_p"] = max(worst[f"{key}_p"],
                                    float(np.linalg.norm(A[:3, 3] - B[:3, 3])))
            worst[f"{key}_r"] = max(worst[f"{key}_r"],
                                    rotation_angle(A[:3, :3].T @ B[:3, :3]))
        down = float(np.clip(T_obj[:3, 0] @ np.array([0.0, 0.0, -1.0]), -1.0, 1.0))
        worst["tilt"] = max(worst["tilt"], math.acos(down))
    return worst


def geometry_problems(worst: dict[str, float]) -> list[str]:
    out = [f"{key}: {worst[key]:.3g} over {tol:g}"
           for key, tol in (("track_p", POSITION_TOL), ("close_p", POSITION_TOL),
                            ("track_r", ANGLE_TOL), ("close_r", ANGLE_TOL))
           if not worst[key] <= tol]
    if not worst["lowest_z"] >= 0.0:
        out.append(f"a joint frame at z = {worst['lowest_z']:.3f} m, below the bases")
    return out


@pytest.mark.parametrize("name", CASES)
def test_oracle_tracking_closure_and_table(name: str, runs: dict[str, Any]) -> None:
    """The object on D(path_t), the follower on its grasp, no joint below the bases."""
    spec, _, _, traj = runs["get"](name)
    problems = geometry_problems(geometry(spec, traj))
    assert not problems, "\n".join(problems)


def test_checks_catch_a_doctored_record(runs: dict[str, Any]) -> None:
    """The same checks fail on a copy of a good record with a grasp 2 mm off, a joint
    jump faster than its limit, or a joint pushed out of its range."""
    spec, _, _, traj = runs["get"]("both_sliding_bar")
    lim = independent_limits(spec)
    for column in ("grasp", "grasp_leader"):
        shifted = {**traj, column: traj[column] + 0.002}
        assert any(p.startswith(("track_p", "close_p"))
                   for p in geometry_problems(geometry(spec, shifted))), column
    jump = dict(traj)
    jump["qf2"] = traj["qf2"].copy()
    jump["qf2"][50:] += 1.1 * lim.speeds["qf2"] * spec.dt
    assert check_speeds(jump, lim) and geometry_problems(geometry(spec, jump))
    out = dict(traj)
    out["ql1"] = traj["ql1"].copy()
    out["ql1"][100:] = lim.bounds["ql1"][1] + np.linspace(0.0, 0.01, traj["t"].size - 100)
    assert check_ranges(out, lim)


def travel(x: np.ndarray) -> float:
    return float(np.sum(np.abs(np.diff(x))))


@pytest.mark.parametrize("name", CASES)
def test_config_does_what_its_header_says(name: str, runs: dict[str, Any]) -> None:
    spec, _, _, traj = runs["get"](name)
    lim = independent_limits(spec)
    speed_ratio = {c: float(np.max(np.abs(np.diff(traj[c])))) / spec.dt / v
                   for c, v in lim.speeds.items() if math.isfinite(v)}
    assert travel(traj["grasp"]) > 0.04  # the follower's grasp slides (m)
    if name == "ur5_pair_sliding_bar":
        assert travel(traj["grasp"]) > 0.1
    elif name == "panda_pair":
        # Capped at 20 deg/s: joints of both arms and the sliding reach their speed
        # limits, and the scale policy slows the bar on some steps.
        assert max(v for c, v in speed_ratio.items() if c.startswith("ql")) > 0.99
        assert max(v for c, v in speed_ratio.items() if c.startswith("qf")) > 0.99
        assert speed_ratio["grasp"] > 0.99
        assert np.sum(traj["scale"] < 1 - 1e-9) > 0
    elif name == "baxter_tray":
        # One robot: both chains share the robot's base; the tray stays level.
        assert np.array_equal(spec.base("leader"), spec.base("follower"))
        np.testing.assert_array_equal(spec.base("leader"), np.eye(4))
        assert geometry(spec, traj)["tilt"] <= ANGLE_TOL  # the tray's x axis stays down
    elif name == "both_sliding_bar":
        assert spec.leader_slides and travel(traj["grasp_leader"]) > 0.01
    elif name == "kinova_pair":
        # Continuous joints 1, 4, 6: no range in the oracle's reading of the URDF either.
        for prefix in ("ql", "qf"):
            for i in (1, 4, 6):
                assert lim.bounds[f"{prefix}{i}"] == (-math.inf, math.inf)
        # The leader's elbow reaches its speed limit and the bar is slowed; the grasp
        # slides to the end of its range (250 mm).
        assert speed_ratio["ql3"] > 0.99 and np.sum(traj["scale"] < 1 - 1e-9) > 0
        assert traj["grasp"].min() == pytest.approx(0.25, abs=1e-6)
    elif name in ("panda_pair_accel", "ur10_panda_pair"):
        # From rest, the sliding (and for the Panda pair a joint) reaches its
        # acceleration limit (recomputed here from the CSV); every joint has one.
        v = {c: np.concatenate([[0.0], np.diff(traj[c]) / spec.dt]) for c in lim.speeds}
        accels = lim.accelerations or {}
        assert all(math.isfinite(a) for a in accels.values())
        accel_ratio = {c: float(np.max(np.abs(np.diff(v[c])))) / spec.dt / a
                       for c, a in accels.items()}
        assert accel_ratio["grasp"] > 0.99 and speed_ratio["grasp"] > 0.99
        if name == "panda_pair_accel":  # and the bar is slowed on some steps
            assert max(accel_ratio[c] for c in accels if c.startswith("q")) > 0.99
            assert np.sum(traj["scale"] < 1 - 1e-9) > 0
