"""Our controller step beside pink's differential-IK step, in one process on one machine.

One run measures, side by side (median and p99 of wall-clock time per call):

1. **pink's UR5 step**, the outside reference the project's speed targets are stated
   against: ``Configuration.update(q)`` + ``solve_ik`` with one ``FrameTask`` on the
   UR5 of example-robot-data (``tool0``), pink's default configuration and velocity
   limits, per installed QP backend (daqp, quadprog, proxqp, osqp).
2. **Our whole controller step** (``DualArmController.step``, nullspace solver: both
   arms' kinematics, assembly, solve, verification) on the PUMA pair of
   ``configs/puma_beam_limits.yaml``, on the states of one recorded rollout, with its
   split (``out.times``) and its ratio to pink's UR5 daqp step (target: at most 0.25).
3. **The 7-dof pair**: the same on ``configs/panda_pair.yaml`` (two Pandas, null space 3)
   and on ``configs/both_sliding_bar.yaml`` (UR5 pair, both grasps sliding); target: at
   most 0.5 of pink's UR5 daqp step.
4. **In-process rollout rate** of ``configs/puma_beam_limits.yaml``: samples per second
   of wall time of ``rollout`` (target: 20,000 steps/s or more).
5. **The step with collision rows** on the collision configs (``puma_beam_pillar``,
   ``ur5_pair_collision``, ``panda_pair_shelf``): the pairs of the scene, the rows per
   step (pairs within the influence distance), the step's median and p99 on the states
   of one rollout with collision avoidance on, the same states with it off, and the step
   interleaved against pink's UR5 daqp step.
6. **pink on the same work**: the PUMA pair's step posed to pink on one Pinocchio model
   (leader, object, the follower's grasp joint, follower), solved by ``solve_ik`` with
   daqp; its velocity is compared with our answer on rollout states, and its time with
   ours (target: pink-on-the-same-work at least 4x our step).
7. (the two ratios again, timed interleaved.)
8. **The step with torque rows** on ``configs/ur5_pair_heavy_bar.yaml``: the torque
   limit's ``constraint`` alone (both arms' statics, their derivatives, 24 rows), the
   whole step with torque limits on, and the same states with them off.
9. **A limit of the user's own, in Python**: the wall of ``examples/custom_limit.py``
   (one row from the follower's tool Jacobian) stacked on the PUMA pair's step, timed
   interleaved with the same step without it on the states of one rollout with the wall
   on: what a user's own Python limit costs per step.

pink and Pinocchio's benchmark-only companions are installed by the ``bench`` extra:
``pip install "dualarm-qp[bench]"``; the UR5 needs the ``robots`` extra
(example-robot-data). Without pink only our numbers (2 to 4) are measured.

    python benchmarks/outside_refs.py [--samples 2000] [--json out.json] [--only torque]

It is a benchmark, not a test: it asserts nothing about speed. The machine may be
shared: medians are reported, with the load average before and after the run.
"""

from __future__ import annotations

import argparse
import dataclasses
import importlib.util
import json
import logging
import sys
import time
import warnings
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from dualarm_qp._compiled import kernel
from dualarm_qp.bench.runner import machine_info
from dualarm_qp.control.rollout import rollout
from dualarm_qp.experiments import build_experiment, load_config
from dualarm_qp.experiments.setup import Experiment
from dualarm_qp.se3 import pose_error
from dualarm_qp.step.bounds import grasp_rate_range
from dualarm_qp.step.limits import RangeLimit, SpeedLimit
from dualarm_qp.step.state import DualArmState

ROOT = Path(__file__).resolve().parent.parent
CONFIGS = ROOT / "configs"

#: The configs whose step is timed with collision rows (section 5), when present.
COLLISION_CONFIGS = ("puma_beam_pillar", "ur5_pair_collision", "panda_pair_shelf")

#: Project targets (stated in the fast-step issue); printed, never asserted.
TARGET_STEP_VS_PINK_UR5 = 0.25  # our step median / pink's UR5 daqp step median, at most
TARGET_7DOF_STEP_VS_PINK_UR5 = 0.5  # the same for the Panda and the both-sliding pair
TARGET_ROLLOUT_STEPS_PER_S = 20_000.0  # in-process rollout rate, at least
TARGET_PINK_SAME_VS_OURS = 4.0  # pink-on-the-same-work median / our step median, at least

State = tuple[DualArmState, float]  # a controller input: state and its scale_max


# --------------------------------------------------------------------------------------
# Timing helpers
# --------------------------------------------------------------------------------------

def stats(t: Sequence[float] | np.ndarray) -> dict[str, float]:
    """Median and p99 of durations given in seconds, in microseconds."""
    a = np.asarray(t, dtype=float)
    return {"median_us": float(np.median(a) * 1e6), "p99_us": float(np.percentile(a, 99) * 1e6)}


def timings(fn: Callable[[int], Any], samples: int, warmup: int = 200) -> np.ndarray:
    """Seconds of ``fn(i)`` for ``i = 0 .. samples-1``, one call at a time, after a warm-up."""
    for i in range(min(warmup, samples)):
        fn(i)
    t = np.empty(samples)
    for i in range(samples):
        t0 = time.perf_counter()
        fn(i)
        t[i] = time.perf_counter() - t0
    return t


def timeit(fn: Callable[[int], Any], samples: int) -> dict[str, float]:
    """Median and p99 [us] of ``fn(i)`` (see :func:`timings`)."""
    return stats(timings(fn, samples))


def interleaved(fn_a: Callable[[int], Any], fn_b: Callable[[int], Any], samples: int,
                warmup: int = 200) -> dict[str, Any]:
    """Time ``fn_a(i)`` and ``fn_b(i)`` alternately, call by call.

    This machine alternates between a fast and a slow state for seconds at a time; two
    rows timed one after the other can see different states. Alternating the calls
    puts both under the same conditions, so their ratio is what the code costs.
    Returns both medians and p99 [us] and the median of the per-pair ratios a / b.
    """
    for i in range(min(warmup, samples)):
        fn_a(i)
        fn_b(i)
    ta, tb = np.empty(samples), np.empty(samples)
    for i in range(samples):
        t0 = time.perf_counter()
        fn_a(i)
        t1 = time.perf_counter()
        fn_b(i)
        t2 = time.perf_counter()
        ta[i], tb[i] = t1 - t0, t2 - t1
    return {"a": stats(ta), "b": stats(tb), "ratio_median": float(np.median(ta / tb))}


def ratio(a: dict[str, float] | None, b: dict[str, float] | None) -> float | None:
    """Ratio of two medians (None when either is missing)."""
    if not isinstance(a, dict) or not isinstance(b, dict):
        return None
    return a["median_us"] / b["median_us"]


# --------------------------------------------------------------------------------------
# Our side: recorded rollout states, the controller step and its split, the rollout rate
# --------------------------------------------------------------------------------------

def experiment(name: str) -> Experiment:
    return build_experiment(load_config(CONFIGS / f"{name}.yaml"), solver="nullspace")


def record_states(exp: Experiment) -> tuple[list[State], dict[str, Any]]:
    """Run one rollout and keep every controller input (state, scale_max) it made.

    The controller's ``step`` is wrapped on the instance, so the recorded inputs are
    exactly the ones the rollout handed it (including the last, shortened sample).
    """
    ctrl = exp.controller()
    states: list[State] = []
    step = ctrl.step
    slowed = 0

    def recording(state: DualArmState, *, scale_max: float = 1.0) -> Any:
        nonlocal slowed
        states.append((state, scale_max))
        o = step(state, scale_max=scale_max)
        slowed += o.scale < scale_max  # the scale policy slowed the path on this step
        return o

    ctrl.step = recording  # type: ignore[method-assign]
    res = rollout(ctrl, exp.initial, duration=exp.duration, limits=exp.limits)
    info = {"samples": len(res.trace), "completed": res.completed, "slowed_steps": slowed,
            "failure": None if res.failure is None else res.failure.message}
    return states, info


def time_controller(exp: Experiment, states: list[State], samples: int) -> dict[str, Any]:
    """Time ``ctrl.step`` cycling over the recorded states, with its split (out.times)."""
    ctrl = exp.controller()
    parts: dict[str, list[float]] = {"kinematics": [], "assembly": [], "solve": [],
                                     "verify": []}
    slowed: list[bool] = []

    def one(i: int) -> None:
        state, scale_max = states[i % len(states)]
        out = ctrl.step(state, scale_max=scale_max)
        tm = out.times
        parts["kinematics"].append(tm.kinematics)
        parts["assembly"].append(tm.assembly)
        parts["solve"].append(tm.solve)
        parts["verify"].append(tm.verify)
        slowed.append(out.scale < scale_max)

    t = timings(one, samples)
    res: dict[str, Any] = {"step": stats(t)}
    for k, v in parts.items():  # the timed calls only (the warm-up calls come first)
        res[k] = stats(v[-samples:])
    # Steps the scale policy slowed (an infeasible full-speed step: a search over the
    # task scale) cost much more than the others: both sets on their own.
    sl = np.asarray(slowed[-samples:])
    res["step, full-speed states"] = stats(t[~sl]) if (~sl).any() else None
    res["step, slowed states"] = stats(t[sl]) if sl.any() else None
    res["states"] = len(states)
    res["n_variables"] = len(ctrl.names)
    return res


def rollout_rate(exp: Experiment, repeats: int) -> dict[str, Any]:
    """Samples per second of wall time of the in-process rollout, ``repeats`` times."""
    rates, samples = [], 0
    for _ in range(repeats):
        ctrl = exp.controller()  # built outside the timed call
        t0 = time.perf_counter()
        res = rollout(ctrl, exp.initial, duration=exp.duration, limits=exp.limits)
        wall = time.perf_counter() - t0
        samples = len(res.trace)
        rates.append(samples / wall)
    return {"samples_per_rollout": samples, "repeats": repeats,
            "steps_per_s": [float(r) for r in rates],
            "steps_per_s_median": float(np.median(rates)),
            "steps_per_s_best": float(np.max(rates))}


def collision_step(name: str, samples: int, pink_step: Callable[[int], Any] | None
                   ) -> dict[str, Any] | None:
    """The step with collision rows on ``name``'s rollout states, and without them.

    Returns None when the config is missing.
    """
    path = CONFIGS / f"{name}.yaml"
    if not path.exists():
        return None
    exp = experiment(name)
    scene = exp.task.scene
    if scene is None or not scene.settings.enabled:
        return None
    states, info = record_states(exp)
    rows: list[int] = []
    ctrl = exp.controller(on_step=lambda out: rows.append(sum(
        1 for r in out.build.problem.row_names if r.startswith("clearance "))))
    for state, scale_max in states:
        ctrl.step(state, scale_max=scale_max)
    with_rows = time_controller(exp, states, samples)
    off = dataclasses.replace(exp, task=dataclasses.replace(exp.task, scene=None))
    without = time_controller(off, states, samples)
    res: dict[str, Any] = {
        "pairs": len(scene.pairs), "states": len(states),
        "rows per step, median": float(np.median(rows)) if rows else 0.0,
        "rows per step, max": int(max(rows, default=0)),
        "step with collision rows": with_rows["step"],
        "  kinematics": with_rows["kinematics"], "  assembly": with_rows["assembly"],
        "  solve": with_rows["solve"],
        "step without them (same states)": without["step"],
        "rollout": info,
    }
    if pink_step is not None:
        ctrl2 = exp.controller()

        def ours(i: int) -> None:
            state, scale_max = states[i % len(states)]
            ctrl2.step(state, scale_max=scale_max)

        res["interleaved / pink ur5 daqp step"] = interleaved(ours, pink_step,
                                                              min(samples, 1000))
    return res


def torque_step(name: str, samples: int) -> dict[str, Any] | None:
    """The torque rows' cost on ``name``'s rollout states: the limit alone, the step on/off.

    Returns None when the config is missing or keeps no torque limits.
    """
    if not (CONFIGS / f"{name}.yaml").exists():
        return None
    exp = experiment(name)
    if not exp.options.torque_limits:
        return None
    states, info = record_states(exp)
    ctrl = exp.controller()
    limit = next(lim for lim in ctrl.builder.limits if lim.name == "torque")
    contexts = [ctrl.builder.build(state).context for state, _ in states]
    active = 0
    for state, scale_max in states:
        out = ctrl.step(state, scale_max=scale_max)
        p = out.build.problem
        rows = [i for i, r in enumerate(p.row_names) if r.startswith("torque ")]
        active += bool(rows) and bool((p.G[rows] @ out.solution.x - p.h[rows] > -1e-6).any())
    with_rows = time_controller(exp, states, samples)
    off = dataclasses.replace(exp, options=dataclasses.replace(exp.options,
                                                               torque_limits=False))
    without = time_controller(off, states, samples)
    return {"states": len(states), "steps with an active torque row": active,
            "rows per step": 2 * (len(ctrl.names) - ctrl.layout.n_grasp),
            "torque limit constraint(ctx) alone": timeit(
                lambda i: limit.constraint(contexts[i % len(contexts)]), samples),
            "step with torque rows": with_rows["step"],
            "  assembly (the rows are built here)": with_rows["assembly"],
            "  solve": with_rows["solve"],
            "step without them (same states)": without["step"], "rollout": info}


# --------------------------------------------------------------------------------------
# 1. pink's UR5 step (the outside reference of the speed targets)
# --------------------------------------------------------------------------------------

def pink_ur5(samples: int, out: dict[str, Any]) -> None:
    import pink
    import pinocchio as pin
    import qpsolvers
    from pink.tasks import FrameTask

    from dualarm_qp import example_robot_arm
    from dualarm_qp.kinematics.robots import example_robot_urdf

    model = pin.buildModelFromUrdf(str(example_robot_urdf("ur5")))
    data = model.createData()
    rng = np.random.default_rng(0)
    mid = 0.5 * (model.lowerPositionLimit + model.upperPositionLimit)
    half = 0.4 * (model.upperPositionLimit - model.lowerPositionLimit)
    qs = mid + half * rng.uniform(-1, 1, (samples, model.nq))

    # Kinematics alone, for scale: our arm layer against bare Pinocchio on the same UR5.
    arm = example_robot_arm("ur5", root="base_link", tip="tool0")
    out["ur5 fk_jacobian, dualarm_qp SerialArm"] = timeit(lambda i: arm.fk_jacobian(qs[i]),
                                                         samples)
    fid = model.getFrameId("tool0")

    def pin_fk_jac(i: int) -> None:
        pin.computeJointJacobians(model, data, qs[i])
        pin.updateFramePlacements(model, data)
        pin.getFrameJacobian(model, data, fid, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)

    out["ur5 fk + frame jacobian, bare pinocchio"] = timeit(pin_fk_jac, samples)

    for backend in ("daqp", "quadprog", "proxqp", "osqp"):
        key = f"pink ur5 update + solve_ik ({backend})"
        if backend not in qpsolvers.available_solvers:
            out[key] = "backend not installed"
            continue
        conf = pink.Configuration(model, model.createData(), qs[0].copy())
        task = FrameTask("tool0", position_cost=1.0, orientation_cost=1.0)
        target = conf.get_transform_frame_to_world("tool0").copy()
        target.translation += np.array([0.01, 0.0, 0.0])
        task.set_target(target)

        def step(i: int, conf: Any = conf, task: Any = task, backend: str = backend) -> None:
            conf.update(qs[i % len(qs)])
            pink.solve_ik(conf, [task], 0.01, solver=backend, safety_break=False)

        out[key] = timeit(step, min(samples, 1000))
        if backend == "daqp":
            out["_daqp_step"] = step  # for the interleaved comparison (not in the JSON)


# --------------------------------------------------------------------------------------
# 5. pink on the same work: the PUMA pair's step on one Pinocchio model
# --------------------------------------------------------------------------------------

class SamePinkStep:
    """The controller step of ``exp`` posed to pink.

    Model: :class:`~dualarm_qp.task.carry.CarryModel` of the task (leader arm, the
    ``object`` frame, the follower's grasp as the joint ``grasp_follower`` carrying the
    ``target`` frame) with the follower arm appended by ``pinocchio.appendModel`` (its
    joints and frames renamed ``f_*``; its base placement is in its model). The tangent
    vector is ``[ql_dot, rate * m, qf_dot]``: the grasp joint's value is
    ``rate * sigma`` (rate 1 on a plane bar, so the joint value is sigma in m).

    The step, as our builder poses it (``dualarm_qp.step.build``):

    * leader tracking, hard: ``J_object x = s V_o(t) + K_l e_l`` (world-aligned twist of
      the object frame) -> a ``FrameTask("object")`` constraint;
    * closure, hard: ``J_f qf_dot - J_target x = K e_c`` -> a ``RelativeFrameTask`` of the
      follower's tool relative to ``target``, as a constraint;
    * the Eq. 37 centring cost ``(x - c)^T W (x - c)`` -> a ``PostureTask`` with cost
      ``sqrt(W)`` per joint (pink's weight enters squared) and target ``q + c dt``;
    * the box (ranges and speed limits, Eqs. 30-36, same rule as the builder) -> a small
      custom ``pink.limits.Limit``, which also gives the centre ``c``.

    pink's constraint rows are ``J Delta q = -e(q)`` with a log-map error and its
    Jacobian ``Jlog6 * J_body``; the targets are placed so that this is our row
    exactly: a frame target ``T exp6(xi)`` turns a ``FrameTask`` into
    ``J_body Delta q = xi`` (because ``Jr(-xi) xi = xi``), and a relative target
    ``T_rf exp6(xi)`` turns a ``RelativeFrameTask`` into ``J_rel Delta q = xi``, where
    ``xi = dt * Ad(R^T) b`` is our right-hand side turned into the frame's body
    coordinates. The feedback gains, the path twist and its scale are ours, read from
    the experiment's options.

    One difference remains, in the closure rows: pink's relative Jacobian is the exact
    relative twist of the tool with respect to the target frame (the target's velocity
    taken at the tool's origin), ours takes each frame's velocity at its own origin; the
    two differ by ``w_target x (p_tool - p_target)``, i.e. by the closure error times the
    object's angular velocity (tiny on the beam, which translates).
    """

    def __init__(self, exp: Experiment) -> None:
        import pink
        import pinocchio as pin
        from pink.limits import Limit
        from pink.tasks import FrameTask, PostureTask, RelativeFrameTask

        from dualarm_qp.task.carry import CarryModel

        task, opts = exp.task, exp.options
        if task.leader_surface is not None or task.contact is not None:
            raise ValueError("only a rigid leader grasp and a grasping follower here")
        self.pin, self.pink = pin, pink
        carry = CarryModel(task.leader, task.surface, task.H1)
        leader_model = pin.Model(carry.model)
        follower_model = pin.Model(task.follower.model)
        tool = task.follower.model.frames[task.follower.tool_frame_id].name
        for i in range(1, follower_model.njoints):
            follower_model.names[i] = "f_" + follower_model.names[i]
        for i in range(1, len(follower_model.frames)):
            frame = follower_model.frames[i]
            frame.name = "f_" + frame.name
            follower_model.frames[i] = frame
        # The arms set ``velocityLimit`` only: Pinocchio 4's ``lowerVelocityLimit`` stays at
        # its default (+max float, above the upper limit), which ``appendModel`` refuses.
        # Set it as Pinocchio's URDF parser does (the magnitude, equal to the upper limit).
        for m in (leader_model, follower_model):
            m.lowerVelocityLimit = m.upperVelocityLimit.copy()
        model = pin.appendModel(leader_model, follower_model, 0, pin.SE3.Identity())
        self.model = model
        n_l, n_f = task.leader.n, task.follower.n
        self.n_l, self.n_f = n_l, n_f
        if model.nq != n_l + 1 + n_f or model.names[n_l + 1] != "grasp_follower":
            raise RuntimeError("unexpected joint order in the appended model")
        self.rate = float(task.surface.slide_joint().rate)
        # Our decision vector [ql, qf, m] <-> pink's tangent [ql, rate*m, qf].
        self.perm = np.r_[np.arange(n_l), n_l + n_f, np.arange(n_l, n_l + n_f)]
        self.unperm = np.argsort(self.perm)
        self.tangent_scale = np.ones(n_l + n_f + 1)
        self.tangent_scale[n_l] = self.rate

        self.dt = opts.dt
        self.traj = task.trajectory
        self.leader_gain = exp.leader_gain
        self.closure_gain = float(opts.correction_gain or 0.0)
        self.surface = task.surface
        inf = np.inf
        limits = opts.velocity_limits
        # Box data in pink's order (positions of the joints; the grasp row is filled per
        # step from the path's range, Eqs. 30-33).
        self.x_min = np.r_[task.leader.q_min, -inf, task.follower.q_min]
        self.x_max = np.r_[task.leader.q_max, inf, task.follower.q_max]
        m_max = opts.grasp_speed_max if limits else inf
        self.v_max = np.r_[task.leader.qd_max if limits else np.full(n_l, inf), m_max,
                           task.follower.qd_max if limits else np.full(n_f, inf)]
        self.recovery = opts.recovery_fraction
        self.everything = np.ones(n_l + n_f + 1, dtype=bool)
        horizon = opts.centre_horizon or opts.dt
        self.centre_factor = opts.dt / horizon
        w = np.empty(n_l + n_f + 1)
        w[:n_l] = opts.leader_joint_weights if opts.leader_joint_weights is not None else 1.0
        w[n_l + n_f:] = opts.grasp_weight
        w[n_l:n_l + n_f] = opts.joint_weights
        # Weight of pink's tangent coordinate: the grasp's is per (joint unit)^2.
        self.weights = w[self.perm] / self.tangent_scale**2

        outer = self

        class StepBox(Limit):
            """The step's box ``lower <= v <= upper`` as ``G dq <= h`` (dq = v dt)."""

            def compute_qp_inequalities(self, configuration: Any, dt: float) -> Any:
                lo, hi = outer.lower, outer.upper
                n = lo.size
                G = np.vstack([np.eye(n), -np.eye(n)])
                h = np.r_[hi * dt, -lo * dt]
                keep = np.isfinite(h)
                return G[keep], h[keep]

        self.box = StepBox()
        q0 = np.zeros(model.nq)
        self.conf = pink.Configuration(model, model.createData(), q0)
        self.tool = "f_" + tool
        self.leader_task = FrameTask("object", position_cost=1.0, orientation_cost=1.0)
        self.closure_task = RelativeFrameTask(self.tool, "target", position_cost=1.0,
                                              orientation_cost=1.0)
        self.centre_task = PostureTask(cost=1.0)
        self.centre_task.cost = np.sqrt(self.weights)  # pink squares it: H = diag(W)
        self.lower = np.zeros(model.nv)
        self.upper = np.zeros(model.nv)

    def q_of(self, state: DualArmState) -> np.ndarray:
        return np.r_[state.q_l, self.rate * state.sigma, state.q_f]

    def _box(self, q: np.ndarray) -> np.ndarray:
        """Lower/upper rates and centre in pink's tangent order; returns the centre."""
        dt, n_l = self.dt, self.n_l
        with np.errstate(invalid="ignore"):
            lo = (self.x_min - q) / dt
            hi = (self.x_max - q) / dt
        surf, s = self.surface, q[n_l] / self.rate
        rho_min, rho_max = grasp_rate_range(surf.point(s), surf.tangent(s), surf.r_min,
                                            surf.r_max, dt)
        lo[n_l] = max(rho_min, (surf.sigma_min - s) / dt)
        hi[n_l] = min(rho_max, (surf.sigma_max - s) / dt)
        # The step's own range and speed limits on these rate ranges, intersected.
        ctx = kernel.Context(lo, hi)
        box = [RangeLimit("range", self.everything, self.v_max, self.recovery).constraint(ctx),
               SpeedLimit("speed", self.v_max).constraint(ctx)]
        lower = np.maximum(box[0].lower, box[1].lower)
        upper = np.minimum(box[0].upper, box[1].upper)
        bounded = np.isfinite(lo) & np.isfinite(hi)
        centre = np.where(bounded, 0.5 * (np.where(bounded, lo, 0) + np.where(bounded, hi, 0)),
                          0.0)
        sc = self.tangent_scale
        self.lower, self.upper = lower * sc, upper * sc
        return centre * self.centre_factor * sc

    def solve(self, state: DualArmState, scale_max: float = 1.0,
              solver: str = "daqp") -> np.ndarray:
        """pink's velocity for ``state``, in our order ``[ql_dot, qf_dot, m]``."""
        pin, dt = self.pin, self.dt
        q = self.q_of(state)
        conf = self.conf
        conf.update(q)
        # Leader row: the object frame makes the twist b_l = s V_o + K_l e_l in dt.
        T_o = conf.get_transform_frame_to_world("object")
        b_l = (scale_max * self.traj.twist(state.t)
               + self.leader_gain * pose_error(self.traj.pose(state.t), T_o.homogeneous))
        R = T_o.rotation
        xi = np.r_[R.T @ b_l[:3], R.T @ b_l[3:]] * dt
        self.leader_task.set_target(T_o * pin.exp6(xi))
        # Closure rows: the tool moves relative to its target by b_c = K e_c in dt.
        T_f = conf.get_transform_frame_to_world(self.tool)
        T_t = conf.get_transform_frame_to_world("target")
        b_c = self.closure_gain * pose_error(T_t.homogeneous, T_f.homogeneous)
        R = T_f.rotation
        xi = np.r_[R.T @ b_c[:3], R.T @ b_c[3:]] * dt
        self.closure_task.set_target(T_t.actInv(T_f) * pin.exp6(xi))
        # Box and centre (Eqs. 30-40), centring cost (Eq. 37).
        centre = self._box(q)
        self.centre_task.set_target(q + dt * centre)
        v = self.pink.solve_ik(conf, [self.centre_task], dt, solver=solver,
                               limits=[self.box],
                               constraints=[self.leader_task, self.closure_task],
                               safety_break=False)
        return (v / self.tangent_scale)[self.unperm]

    def box_ours_order(self) -> tuple[np.ndarray, np.ndarray]:
        sc = self.tangent_scale
        return (self.lower / sc)[self.unperm], (self.upper / sc)[self.unperm]


def pink_same_work(exp: Experiment, states: list[State], samples: int, n_compare: int,
                   out: dict[str, Any]) -> None:
    """Agreement of pink's velocity with our nullspace answer, and pink's step time."""
    same = SamePinkStep(exp)
    ctrl = exp.controller()
    idx = np.unique(np.linspace(0, len(states) - 1, min(n_compare, len(states))).astype(int))
    import qpsolvers

    diff, box_diff, w_dp, diff_exact, diff_daqp = [], [], [], [], []
    skipped = 0
    for k in idx:
        state, scale_max = states[k]
        o = ctrl.step(state, scale_max=scale_max)
        if o.scale < scale_max or not o.applied:  # a slowed step: not the same equality
            skipped += 1
            continue
        x = np.r_[o.ql_dot, o.qf_dot, o.m]
        v = same.solve(state, scale_max)
        diff.append(float(np.abs(v - x).max()))
        lo, hi = same.box_ours_order()
        p = o.build.problem
        box_diff.append(float(max(np.abs(lo - p.lower).max(), np.abs(hi - p.upper).max())))
        # Size of the term the two closure Jacobians differ by: |w_target x dp| [m/s].
        kin = o.build.carry
        w_t = kin.J_target[3:] @ np.r_[x[:same.n_l], x[-1]]
        dp = o.build.T_f[:3, 3] - kin.T_target[:3, 3]
        w_dp.append(float(np.linalg.norm(np.cross(w_t, dp))))
        # Diagnostics: daqp on our own problem (same answer as nullspace?), and on our
        # problem with pink's exact relative closure Jacobian (the linear closure rows
        # take the target's velocity at the tool: + [dp]x w_target). If pink's answer
        # equals the latter, the closure Jacobian explains the whole difference.
        diff_daqp.append(float(np.abs(_daqp(qpsolvers, p.A, p) - x).max()))
        A = p.A.copy()
        cols = np.r_[np.arange(same.n_l), p.n - 1]
        A[6:9, cols] += _skew(dp) @ kin.J_target[3:]
        diff_exact.append(float(np.abs(_daqp(qpsolvers, A, p) - v).max()))
    d = np.asarray(diff)
    out["states compared"] = len(diff)
    out["states skipped (slowed by the scale policy)"] = skipped
    out["max abs diff, pink vs ours [rad/s, m/s]"] = float(d.max()) if d.size else None
    out["median abs diff, pink vs ours"] = float(np.median(d)) if d.size else None
    out["max abs diff, box pink vs ours"] = float(max(box_diff)) if box_diff else None
    out["max |w_target x (p_tool - p_target)| [m/s]"] = float(max(w_dp)) if w_dp else None
    out["max abs diff, daqp on our problem vs ours"] = max(diff_daqp, default=None)
    out["max abs diff, pink vs our problem with exact closure Jacobian"] = max(
        diff_exact, default=None)
    out["pink same work update + solve_ik (daqp)"] = timeit(
        lambda i: same.solve(*states[i % len(states)]), samples)
    out["_step"] = lambda i: same.solve(*states[i % len(states)])


def _skew(u: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -u[2], u[1]], [u[2], 0.0, -u[0]], [-u[1], u[0], 0.0]])


def _daqp(qpsolvers: Any, A: np.ndarray, p: Any) -> np.ndarray:
    """daqp (through qpsolvers) on ``min (x-c)^T W (x-c), A x = b, lower <= x <= upper``."""
    W = np.diag(p.weights)
    x = qpsolvers.solve_qp(W, -W @ p.center, A=A, b=p.b, lb=p.lower, ub=p.upper,
                           solver="daqp")
    return np.full(p.n, np.nan) if x is None else x


# --------------------------------------------------------------------------------------
# Report
# --------------------------------------------------------------------------------------

def fmt(v: Any) -> str:
    if isinstance(v, dict) and "median_us" in v:
        return f"median {v['median_us']:9.1f} us   p99 {v['p99_us']:9.1f} us"
    if isinstance(v, float):
        return f"{v:.3g}"
    return str(v)


def print_section(title: str, rows: dict[str, Any]) -> None:
    print(f"\n== {title}")
    width = max((len(k) for k in rows), default=0)
    for k, v in rows.items():
        if (isinstance(v, dict) and "median_us" not in v) or k.startswith("ratio"):
            continue  # nested results; ratios are printed on their own line
        print(f"  {k:<{width}}  {fmt(v)}")


def own_limit_step(samples: int) -> dict[str, Any]:
    """The PUMA pair's step with the wall of ``examples/custom_limit.py`` and without it.

    The wall is placed as the example places it (150 mm from the follower tool's start);
    both controllers step through the states of one rollout with the wall on (where the
    wall binds), alternately, call by call.
    """
    spec = importlib.util.spec_from_file_location("custom_limit",
                                                  ROOT / "examples" / "custom_limit.py")
    assert spec is not None and spec.loader is not None
    example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(example)
    plain = experiment("puma_beam_limits")
    start = plain.task.follower.fk(plain.initial.q_f)[:3, 3]
    wall = example.Wall(normal=[0.0, -1.0, 0.0], offset=-(start[1] - 0.150))
    walled = build_experiment(load_config(CONFIGS / "puma_beam_limits.yaml"),
                              solver="nullspace", limits=[wall])
    states, info = record_states(walled)
    wall_calls: list[float] = []
    constraint = wall.constraint

    def timed_constraint(ctx: Any) -> Any:  # the limit's own Python call, timed
        t0 = time.perf_counter()
        c = constraint(ctx)
        wall_calls.append(time.perf_counter() - t0)
        return c

    wall.constraint = timed_constraint
    assembly: dict[str, list[float]] = {"a": [], "b": []}
    with_wall = walled.controller(on_step=lambda out: assembly["a"].append(
        out.times.assembly))
    without = plain.controller(on_step=lambda out: assembly["b"].append(out.times.assembly))

    def a(i: int) -> None:
        state, scale_max = states[i % len(states)]
        with_wall.step(state, scale_max=scale_max)

    def b(i: int) -> None:
        state, scale_max = states[i % len(states)]
        without.step(state, scale_max=scale_max)

    res = interleaved(a, b, samples)
    return {"states": len(states), "rollout": info,
            "step with the wall": res["a"], "step without it (same states)": res["b"],
            "ratio with / without": res["ratio_median"],
            "  assembly with the wall": stats(assembly["a"][-samples:]),
            "  assembly without it": stats(assembly["b"][-samples:]),
            "  the wall's constraint(ctx) call": stats(wall_calls[-samples:])}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=2000,
                    help="timed calls per row (pink's UR5 backends: at most 1000)")
    ap.add_argument("--rollouts", type=int, default=5, help="rollouts timed for the rate")
    ap.add_argument("--compare", type=int, default=200,
                    help="rollout states on which pink's velocity is compared with ours")
    ap.add_argument("--json", type=Path, default=None)
    ap.add_argument("--only", choices=["torque", "wall"], default=None,
                    help="measure one section only (8: torque rows, 9: the user's wall)")
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore")  # qpsolvers' sparse-conversion notices for osqp
    logging.getLogger().setLevel(logging.ERROR)  # pink's out-of-limit notices
    n = args.samples
    out: dict[str, Any] = {"machine_before": machine_info(), "samples": n}
    if args.only is not None:
        if args.only == "torque":
            res = torque_step("ur5_pair_heavy_bar", n)
            out["torque_step"] = res
            print_torque(res)
        else:
            res = own_limit_step(n)
            out["own_limit_step"] = res
            own = res["  the wall's constraint(ctx) call"]["median_us"]
            print(f"the step with the wall / without: {res['ratio with / without']:.3f}x "
                  f"(medians {res['step with the wall']['median_us']:.1f} us and "
                  f"{res['step without it (same states)']['median_us']:.1f} us; the wall's "
                  f"own call {own:.1f} us)")
        if args.json:
            args.json.parent.mkdir(parents=True, exist_ok=True)
            args.json.write_text(json.dumps(out, indent=2) + "\n")
        return 0
    try:
        import pink
        import pinocchio as pin
    except ImportError:
        pink = None
        out["pink"] = "not installed: pip install 'dualarm-qp[bench]'"
    else:
        out["pink version"] = pink.__version__
        out["pinocchio version"] = pin.__version__

    # 1. pink's UR5 step.
    ref: dict[str, Any] = {}
    if pink is not None:
        try:
            pink_ur5(n, ref)
        except ImportError as err:  # example-robot-data missing
            ref["error"] = f"{err}: pip install 'dualarm-qp[robots]'"
    out["pink_ur5"] = ref
    pink_ref = ref.get("pink ur5 update + solve_ik (daqp)")

    # 2, 3. Our controller step on recorded rollout states.
    ours: dict[str, Any] = {}
    states_of: dict[str, list[State]] = {}
    exps: dict[str, Experiment] = {}
    for name in ("puma_beam_limits", "panda_pair", "both_sliding_bar"):
        exp = exps[name] = experiment(name)
        states, info = record_states(exp)
        states_of[name] = states
        res = time_controller(exp, states, n)
        res["rollout"] = info
        res["ratio to pink ur5 daqp"] = ratio(res["step"], pink_ref)
        ours[name] = res
    out["controller_step"] = ours

    # 4. In-process rollout rate.
    rate = rollout_rate(exps["puma_beam_limits"], args.rollouts)
    out["rollout_rate_puma_beam_limits"] = rate

    # 5. The step with collision rows.
    collisions: dict[str, Any] = {}
    for name in COLLISION_CONFIGS:
        res = collision_step(name, n, ref.get("_daqp_step"))
        if res is not None:
            collisions[name] = res
    out["collision_step"] = collisions

    # 6. pink on the same work.
    same: dict[str, Any] = {}
    if pink is not None:
        pink_same_work(exps["puma_beam_limits"], states_of["puma_beam_limits"], n,
                       args.compare, same)
        same["ratio pink same work / our step"] = ratio(
            same["pink same work update + solve_ik (daqp)"],
            ours["puma_beam_limits"]["step"])
    out["pink_same_work_puma_beam_limits"] = same

    # 7. The two ratios again, timed interleaved (call by call), so that both sides see
    # the same machine state: pink's UR5 step against our PUMA step, and pink on the
    # same work against our step, on the same recorded states.
    paired: dict[str, Any] = {}
    puma_states = states_of["puma_beam_limits"]
    ctrl = exps["puma_beam_limits"].controller()

    def our_step(i: int) -> None:
        ctrl.step(*puma_states[i % len(puma_states)][:1],
                  scale_max=puma_states[i % len(puma_states)][1])

    ur5_step = ref.pop("_daqp_step", None)
    if ur5_step is not None:
        # The UR5 row times its first 1000 configurations (pink finds no solution at some
        # of the others): the same here.
        paired["our step / pink ur5 daqp step"] = interleaved(our_step, ur5_step, min(n, 1000))
    same_step = same.pop("_step", None)
    if same_step is not None:
        paired["pink same work / our step"] = interleaved(same_step, our_step, n)
    out["interleaved"] = paired

    # 8. The step with torque rows.
    out["torque_step"] = torque_step("ur5_pair_heavy_bar", n)

    # 9. A limit of the user's own, in Python.
    own = own_limit_step(n)
    out["own_python_limit_puma_beam_limits"] = own

    out["targets"] = {
        "our step / pink ur5 daqp step, at most": TARGET_STEP_VS_PINK_UR5,
        "panda and both-sliding step / pink ur5 daqp step, at most":
            TARGET_7DOF_STEP_VS_PINK_UR5,
        "rollout steps/s, at least": TARGET_ROLLOUT_STEPS_PER_S,
        "pink same work / our step, at least": TARGET_PINK_SAME_VS_OURS,
    }
    out["machine_after"] = machine_info()

    # ---- table -----------------------------------------------------------------------
    mb, ma = out["machine_before"], out["machine_after"]
    print(f"machine: {mb['cpu']}, {mb['cpus']} cpus, python {mb['python']}, numpy "
          f"{mb['numpy']}; load average before {[round(x, 2) for x in mb['load_average']]}, "
          f"after {[round(x, 2) for x in ma['load_average']]}")
    print(f"pink {out.get('pink version', '-')}, pinocchio {out.get('pinocchio version', '-')}"
          f", samples per row {n}")
    if ref:
        print_section("1. pink's UR5 step (default limits, one FrameTask)", ref)
    for name, res in ours.items():
        rows = {"controller step": res["step"]}
        rows.update({f"  {k}": res[k] for k in ("kinematics", "assembly", "solve", "verify")})
        for k in ("step, full-speed states", "step, slowed states"):
            if res[k] is not None:
                rows[k] = res[k]
        print_section(f"{'2' if name == 'puma_beam_limits' else '3'}. our step, {name} "
                      f"({res['n_variables']} variables, {res['states']} rollout states, "
                      f"{res['rollout']['slowed_steps']} of them slowed by the scale policy)",
                      rows)
        r = res["ratio to pink ur5 daqp"]
        if r is not None:
            target = (TARGET_STEP_VS_PINK_UR5 if name == "puma_beam_limits"
                      else TARGET_7DOF_STEP_VS_PINK_UR5)
            print(f"  ratio to pink's UR5 daqp step: {r:.2f}x (target at most {target}x)")
    print("\n== 4. in-process rollout rate, puma_beam_limits "
          f"({rate['samples_per_rollout']} samples, {rate['repeats']} rollouts)")
    print(f"  steps/s median {rate['steps_per_s_median']:,.0f}, best "
          f"{rate['steps_per_s_best']:,.0f} (target at least {TARGET_ROLLOUT_STEPS_PER_S:,.0f})")
    for name, res in collisions.items():
        rows = {k: v for k, v in res.items() if isinstance(v, dict) and "median_us" in v}
        print_section(f"5. our step with collision rows, {name} ({res['pairs']} pairs, "
                      f"{res['states']} rollout states; rows per step: median "
                      f"{res['rows per step, median']:g}, max {res['rows per step, max']})",
                      rows)
        inter = res.get("interleaved / pink ur5 daqp step")
        if inter is not None:
            print(f"  interleaved with pink's UR5 daqp step: {inter['ratio_median']:.2f}x "
                  f"(medians {inter['a']['median_us']:.1f} us and "
                  f"{inter['b']['median_us']:.1f} us)")
    if same:
        print_section("6. pink on the same work, puma_beam_limits (daqp)", same)
        print(f"  our step {fmt(ours['puma_beam_limits']['step'])}")
        print(f"  ratio pink same work / our step: "
              f"{same['ratio pink same work / our step']:.2f}x (target at least "
              f"{TARGET_PINK_SAME_VS_OURS}x)")
    if paired:
        print("\n== 7. the ratios timed interleaved (call by call, the same machine state)")
        for k, v in paired.items():
            print(f"  {k:<34} {v['ratio_median']:.2f}x   (medians {v['a']['median_us']:.1f} "
                  f"us and {v['b']['median_us']:.1f} us)")
    print_torque(out["torque_step"])
    print(f"\n== 9. a limit of the user's own in Python (examples/custom_limit.py's wall), "
          f"puma_beam_limits ({own['states']} rollout states with the wall on)")
    for k in ("step with the wall", "step without it (same states)",
              "  assembly with the wall", "  assembly without it",
              "  the wall's constraint(ctx) call"):
        print(f"  {k:<34} {fmt(own[k])}")
    print(f"  interleaved, with / without: {own['ratio with / without']:.2f}x (the solve "
          "differs too: the wall changes which limits bind)")
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(out, indent=2) + "\n")
    return 0


def print_torque(res: dict[str, Any] | None) -> None:
    """Print section 8 (nothing when the config keeps no torque limits)."""
    if res is None:
        return
    rows = {k: v for k, v in res.items() if isinstance(v, dict) and "median_us" in v}
    print_section(f"8. our step with torque rows, ur5_pair_heavy_bar ({res['states']} rollout "
                  f"states, {res['rows per step']} rows per step, a torque row active on "
                  f"{res['steps with an active torque row']} steps)", rows)


if __name__ == "__main__":
    sys.exit(main())
