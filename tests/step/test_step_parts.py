"""The step's one loop equals its parts asked one by one.

``StepBuilder.build`` is one kernel call (``kernel.Step.build``): both arms' kinematics,
the rates to the range ends, then every task, cost term and limit asked in turn and
their pieces stacked. Each part can also be asked on its own: the kinematics
(:func:`both_arms`), every task's ``equality(ctx)``, the centring's ``quadratic(ctx)``
and every limit's ``constraint(ctx)``. The problem the loop stacks must equal, bit for
bit, the one those separate calls give, on the shipped configurations (one and two
sliding grasps, a support, acceleration limits, collision and torque rows, the paper's
open leader box) at perturbed states with a random last command.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from test_braking_bound import numpy_braking_bound

from dualarm_qp._compiled import kernel
from dualarm_qp.experiments import build_experiment, load_config
from dualarm_qp.step.bounds import grasp_rate_range, grasp_rates
from dualarm_qp.step.build import StepBuilder
from dualarm_qp.step.kinematics import both_arms
from dualarm_qp.step.stacking import PIN_RTOL
from dualarm_qp.step.state import DualArmState

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
NAMES = ("puma_beam_limits", "both_sliding_bar", "puma_beam_support", "panda_pair_accel",
         "ur5_pair_collision", "ur5_pair_heavy_bar", "puma_beam_accel")


def _experiment(name: str, solver: str = "nullspace"):
    path = CONFIGS / f"{name}.yaml"
    return build_experiment(load_config(path), str(path), solver=solver)


@pytest.fixture(scope="module", params=[*NAMES, "puma_beam_limits/reference"])
def case(request: pytest.FixtureRequest):
    name, _, solver = request.param.partition("/")
    exp = _experiment(name, solver or "nullspace")
    return exp, exp.controller().builder


def _state(exp, builder: StepBuilder, rng: np.random.Generator):
    s0 = exp.initial
    two = builder.layout.n_grasp == 2
    return DualArmState(float(rng.uniform(0.0, exp.duration)),
                        s0.q_l + rng.normal(0.0, 0.02, s0.q_l.shape),
                        s0.q_f + rng.normal(0.0, 0.02, s0.q_f.shape),
                        s0.sigma + float(rng.normal(0.0, 0.005)),
                        s0.sigma_leader + (float(rng.normal(0.0, 0.005)) if two else 0.0))


def _equal(a: np.ndarray, b: np.ndarray, what: str) -> None:
    """Bit for bit: the values and the signs of zeros."""
    assert a.shape == b.shape and np.array_equal(a, b), what
    assert np.array_equal(np.signbit(a), np.signbit(b)), f"{what}: the sign of a zero"


@settings(max_examples=12, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), scale=st.sampled_from([1.0, 0.5]))
def test_the_loop_equals_the_parts_asked_one_by_one(case, seed: int, scale: float) -> None:
    exp, builder = case
    rng = np.random.default_rng(seed)
    state = _state(exp, builder, rng)
    x_applied = rng.normal(0.0, 0.3, builder.n)
    build = builder.build(state, scale_max=scale, x_applied=x_applied)
    ctx, problem = build.context, build.problem
    assert ctx is not None
    # The kinematics, at the placement the step used.
    arms = both_arms(builder.carry, exp.task.follower, ctx.state.q_l, ctx.state.q_f,
                     state.sigma, state.sigma_leader, exp.task.trajectory.pose(state.t))
    for field in ("T_tool", "J_tool", "T_object", "J_object", "T_target", "J_target"):
        _equal(getattr(ctx.carry, field), getattr(arms.carry, field), field)
    _equal(ctx.T_f, arms.T_f, "T_f")
    _equal(ctx.J_f, arms.J_f, "J_f")
    _equal(ctx.leader_error, arms.leader_error, "leader_error")
    _equal(ctx.closure_error, arms.closure_error, "closure_error")
    assert ctx.sigma_min == arms.sigma_min
    # The equality (every task's rows in turn) and the centres.
    rows = [task.equality(ctx) for task in builder.tasks]
    _equal(problem.A, np.vstack([eq.A for eq in rows]), "A")
    _equal(problem.b, np.concatenate([eq.b for eq in rows]), "b")
    assert problem.eq_names == tuple(name for eq in rows for name in eq.names)
    _equal(problem.center, builder.cost.quadratic(ctx).center, "center")
    _equal(problem.weights, builder.cost.quadratic(ctx).weights, "weights")
    # The box: every limit's own constraint(ctx), intersected in the limits' order.
    lowers, lower_ids, uppers, upper_ids = [], [], [], []
    for k, limit in enumerate(builder.limits):
        c = limit.constraint(ctx)
        if c.lower is not None:
            lowers.append(np.asarray(c.lower, dtype=float))
            lower_ids.append(k)
        if c.upper is not None:
            uppers.append(np.asarray(c.upper, dtype=float))
            upper_ids.append(k)
    n = builder.n
    box = kernel.intersect_boxes(
        np.array(lowers).reshape(-1, n), lower_ids, np.array(uppers).reshape(-1, n),
        upper_ids, n, PIN_RTOL)
    assert box.nan_limit < 0
    _equal(problem.lower, box.lower, "lower")
    _equal(problem.upper, box.upper, "upper")
    labels = [limit.name for limit in builder.limits]
    assert problem.lower_by == tuple(labels[i] if i >= 0 else "" for i in box.lower_by)
    assert problem.upper_by == tuple(labels[i] if i >= 0 else "" for i in box.upper_by)
    # The grasps' rates to their range ends (the kernel's own for a straight grasp), and
    # the variables that recover.
    _equal_grasp_rates(builder, ctx)
    _equal(build.recovering, ctx.outside & builder._ranged, "recovering")
    assert build.recovers is bool((ctx.outside & builder._ranged).any())  # the kernel's flag


def python_era_grasp_rate_range(r, s_star, r_min, r_max, dt: float) -> tuple[float, float]:
    """Eqs. 30-31 as the Python step computed them, on Python floats (the reference)."""
    rho_min, rho_max = -math.inf, math.inf
    for ri, si, lo, hi in zip(np.asarray(r, dtype=float).tolist(),
                              np.asarray(s_star, dtype=float).tolist(),
                              np.asarray(r_min, dtype=float).tolist(),
                              np.asarray(r_max, dtype=float).tolist(), strict=True):
        if abs(si) < 1e-12:
            continue
        a = (lo - ri) / (si * dt)
        b = (hi - ri) / (si * dt)
        rho_min = max(rho_min, min(a, b))
        rho_max = min(rho_max, max(a, b))
    return rho_min, rho_max


def python_era_grasp_rates(surf, s: float, dt: float) -> tuple[float, float]:
    """A grasp's rates to its range ends as the Python step computed them."""
    rho_min, rho_max = python_era_grasp_rate_range(surf.point(s), surf.tangent(s),
                                                   surf.r_min, surf.r_max, dt)
    return max(rho_min, (surf.sigma_min - s) / dt), min(rho_max, (surf.sigma_max - s) / dt)


def _same_float(a: float, b: float) -> bool:
    """Bit for bit: equal with the same sign of a zero, or both NaN."""
    if math.isnan(a) or math.isnan(b):
        return math.isnan(a) and math.isnan(b)
    return a == b and math.copysign(1.0, a) == math.copysign(1.0, b)


def _equal_grasp_rates(builder: StepBuilder, ctx) -> None:
    k = builder.layout.n_grasp
    sigmas = (ctx.state.sigma, ctx.state.sigma_leader)[:k]
    for g, (surf, s) in enumerate(zip(ctx.surfaces, sigmas, strict=True)):
        lo, hi = python_era_grasp_rates(surf, s, builder.options.dt)
        i = builder.layout.n_l + builder.layout.n_f + g
        assert _same_float(float(ctx.rate_lo[i]), lo), (g, ctx.rate_lo[i], lo)
        assert _same_float(float(ctx.rate_hi[i]), hi), (g, ctx.rate_hi[i], hi)


@settings(max_examples=40, deadline=None)
@given(name=st.sampled_from(["puma_beam_limits", "both_sliding_bar", "curved_bar_waypoints",
                             "ur5_pair_sliding_bar"]),
       offsets=st.tuples(st.floats(-0.6, 0.6), st.floats(-0.6, 0.6)))
@pytest.mark.slow
def test_the_grasp_rates_equal_the_python_era_ones(name: str,
                                                   offsets: tuple[float, float]) -> None:
    """Straight grasps (computed in the kernel) and curved ones, inside and outside."""
    exp = _experiment(name)
    builder = exp.controller().builder
    assert builder._step.grasp_lines == (name != "curved_bar_waypoints")
    s0 = exp.initial
    state = DualArmState(s0.t, s0.q_l, s0.q_f, s0.sigma + offsets[0],
                         s0.sigma_leader + (offsets[1] if builder.layout.n_grasp == 2
                                            else 0.0))
    ctx = builder.build(state).context
    _equal_grasp_rates(builder, ctx)


@settings(max_examples=300, deadline=None)
@given(vectors=st.lists(st.floats(allow_nan=True, allow_infinity=True, width=64),
                        min_size=12, max_size=12),
       tiny=st.sampled_from([0.0, -0.0, 1e-13, -1e-13, 1e-12, 1.0]),
       dt=st.sampled_from([0.01, 0.001, 1e-6]))
def test_the_kernel_grasp_rate_range_is_the_python_era_one(vectors: list[float],
                                                           tiny: float, dt: float) -> None:
    r, s_star, r_min, r_max = (np.array(vectors[i:i + 3]) for i in range(0, 12, 3))
    s_star[0] = tiny  # a component below the 1e-12 cut, on it, or above it
    got = grasp_rate_range(r, s_star, r_min, r_max, dt)
    want = python_era_grasp_rate_range(r, s_star, r_min, r_max, dt)
    assert all(_same_float(g, w) for g, w in zip(got, want, strict=True)), (got, want)


def test_the_standard_limits_are_compiled_and_the_torque_limit_is_python() -> None:
    """Recognised by their type: the kernel's part classes, and a Python override."""
    builder = _experiment("ur5_pair_heavy_bar").controller().builder
    compiled = (kernel.RangeLimit, kernel.SpeedLimit, kernel.AccelerationLimit,
                kernel.CollisionLimit)
    names = {limit.name for limit in builder.limits if isinstance(limit, compiled)}
    assert {"joint range", "grasp range", "joint speed", "grasp speed"} <= names
    torque = next(limit for limit in builder.limits if limit.name == "torque")
    assert isinstance(torque, kernel.Limit) and not isinstance(torque, compiled)
    collision = _experiment("ur5_pair_collision").controller().builder
    assert any(isinstance(limit, kernel.CollisionLimit) for limit in collision.limits)
    assert all(isinstance(t, (kernel.ObjectPathTask, kernel.GraspClosureTask))
               for t in builder.tasks)
    assert isinstance(builder.cost, kernel.CentringCost)


def test_the_kernel_refuses_misshaped_input() -> None:
    exp = _experiment("puma_beam_limits")
    builder = exp.controller().builder
    step = builder._step
    carry, follower = builder.carry, exp.task.follower
    q = carry.configuration(exp.initial.q_l, exp.initial.sigma)
    good = dict(carry=carry.chain, q_carry=q, col_rate=carry.columns[1],
                follower=follower.chain, q_f=exp.initial.q_f, T_D=np.eye(4),
                twist=np.zeros(6), sigmas=np.zeros(1), grasp_lo=np.zeros(0),
                grasp_hi=np.zeros(0), x_applied=np.zeros(builder.n), t=0.0, scale_max=1.0,
                user=None)
    assert step.grasp_lines  # the paper's bar is straight: no grasp rates are given
    step.build(kernel.StepOut(), **good)
    for key, bad in (("q_carry", q[:-1]), ("q_f", exp.initial.q_f[:3]),
                     ("sigmas", np.zeros(2)), ("x_applied", np.zeros(3)),
                     ("col_rate", np.ones(2))):
        with pytest.raises(ValueError):
            step.build(kernel.StepOut(), **{**good, key: bad})
    with pytest.raises(ValueError, match="one line per grasp"):
        step.add_grasp_line(np.zeros(3), np.ones(3), np.zeros(3), np.ones(3), 0.0, 1.0)
    # Without the grasps' lines the rates are given, one per grasp.
    curved = _experiment("curved_bar_waypoints")
    loose = curved.controller().builder
    assert not loose._step.grasp_lines
    c_q = loose.carry.configuration(curved.initial.q_l, curved.initial.sigma)
    given = dict(good, carry=loose.carry.chain, q_carry=c_q, col_rate=loose.carry.columns[1],
                 follower=curved.task.follower.chain, q_f=curved.initial.q_f,
                 x_applied=np.zeros(loose.n), grasp_lo=np.zeros(1), grasp_hi=np.zeros(1))
    loose._step.build(kernel.StepOut(), **given)
    for key in ("grasp_lo", "grasp_hi"):
        with pytest.raises(ValueError):
            loose._step.build(kernel.StepOut(), **{**given, key: np.zeros(0)})


class _PythonBox:
    """A user's box limit in Python (no compiled form)."""

    gives_rows = False

    def __init__(self, name: str, scale: float) -> None:
        self.name, self.scale = name, scale

    def constraint(self, ctx):
        from dualarm_qp.step.parts import Constraint
        n = ctx.layout.n
        return Constraint(lower=-self.scale * np.ones(n), upper=self.scale * np.ones(n))


def test_python_and_compiled_boxes_are_intersected_in_the_limits_order() -> None:
    from dualarm_qp.step.limits import SpeedLimit

    exp = _experiment("puma_beam_limits")
    base = exp.controller().builder
    n = base.n
    # A Python box between two compiled ones, ties included (the earlier limit names it).
    extra = (_PythonBox("python box", 0.5), SpeedLimit("user speed", np.full(n, 0.5)),
             _PythonBox("python box 2", 0.25))
    builder = StepBuilder(exp.task, base.options, limits=extra)
    ctx = builder.build(exp.initial).context
    problem = builder.build(exp.initial).problem
    lowers, uppers = [], []
    for limit in builder.limits:
        c = limit.constraint(ctx)
        lowers.append(np.asarray(c.lower, dtype=float))
        uppers.append(np.asarray(c.upper, dtype=float))
    ids = list(range(len(builder.limits)))
    box = kernel.intersect_boxes(np.array(lowers), ids, np.array(uppers), ids, n, PIN_RTOL)
    _equal(problem.lower, box.lower, "lower")
    _equal(problem.upper, box.upper, "upper")
    labels = [limit.name for limit in builder.limits]
    assert problem.lower_by == tuple(labels[i] if i >= 0 else "" for i in box.lower_by)
    assert problem.upper_by == tuple(labels[i] if i >= 0 else "" for i in box.upper_by)
    assert "python box 2" in problem.lower_by


def numpy_acceleration_box(a_max, dt, lo, hi, x0):
    """The Python-era acceleration box (numpy), kept as the reference of the kernel's."""
    delta = a_max * dt
    with np.errstate(invalid="ignore"):
        lower = x0 - delta
        upper = x0 + delta

    d_up = hi * dt
    d_lo = -lo * dt
    v_up = np.where(d_up >= 0.0, numpy_braking_bound(d_up, delta, dt), np.inf)
    v_lo = np.where(d_lo >= 0.0, numpy_braking_bound(d_lo, delta, dt), np.inf)
    return np.maximum(lower, -v_lo), np.minimum(upper, v_up)


@settings(max_examples=100, deadline=None)
@given(seed=st.integers(0, 2**31 - 1))
def test_the_acceleration_box_equals_the_python_era_box(seed: int) -> None:
    from dualarm_qp.step.limits import AccelerationLimit

    rng = np.random.default_rng(seed)
    n, dt = 16, float(rng.choice([0.01, 0.002, 0.0137]))
    a = rng.uniform(0.5, 50.0, n)
    a[rng.random(n) < 0.15] = np.inf
    delta = a * dt
    # Ties and zeros of both signs: at the range end, at rest, exactly one step of delta.
    lo = rng.choice([-0.0, 0.0, -1.0, -np.inf, 0.3], n) / dt
    hi = rng.choice([-0.0, 0.0, 1.0, np.inf, -0.3], n) / dt
    x0 = np.where(rng.random(n) < 0.3, rng.choice([1.0, -1.0], n) * delta,
                  rng.choice([0.0, -0.0, 0.5, -0.2], n))
    x0 = np.where(np.isfinite(x0), x0, 0.0)
    box = AccelerationLimit(a, dt).constraint(kernel.Context(lo, hi, x0, dt=dt))
    lower, upper = numpy_acceleration_box(a, dt, lo, hi, x0)
    _equal(box.lower, lower, "lower")
    _equal(box.upper, upper, "upper")


def test_a_bad_last_command_is_a_clear_error() -> None:
    from dualarm_qp.errors import InvalidInputError, NonFiniteError, ShapeError

    exp = _experiment("puma_beam_accel")
    builder = exp.controller().builder
    n = builder.n
    bad = np.zeros(n)
    bad[0] = np.nan
    with pytest.raises(NonFiniteError, match="x_applied"):
        builder.build(exp.initial, x_applied=bad)
    with pytest.raises(ShapeError, match="x_applied"):
        builder.build(exp.initial, x_applied=np.zeros(3))
    for name in ("x_applied", "x_prev"):  # never a silently dropped imaginary part
        with pytest.raises(InvalidInputError, match=f"{name} is not real numbers"):
            builder.build(exp.initial, **{name: np.zeros(n) + 1e-3j})
    ok = builder.build(exp.initial, x_applied=[0.0] * n).problem  # a list is numbers
    _equal(ok.lower, builder.build(exp.initial, x_applied=np.zeros(n)).problem.lower, "lower")


def test_a_limit_keeps_its_callers_array_writable() -> None:
    from dualarm_qp.step.limits import SpeedLimit

    v = np.full(5, 0.7)
    limit = SpeedLimit("cap", v)
    v[0] = 0.1  # the caller's array is still the caller's
    assert limit.constraint(kernel.Context(np.zeros(5), np.zeros(5))).upper[0] == 0.7


def test_a_subclass_that_overrides_constraint_runs_its_own() -> None:
    from dualarm_qp.step.limits import SpeedLimit
    from dualarm_qp.step.parts import Constraint

    class Tighter(SpeedLimit):
        def constraint(self, ctx):
            n = ctx.layout.n
            return Constraint(lower=np.full(n, -0.01), upper=np.full(n, 0.01))

    exp = _experiment("puma_beam_limits")
    base = exp.controller().builder
    builder = StepBuilder(exp.task, base.options,
                          limits=(Tighter("tighter", np.full(base.n, 2.0)),))
    problem = builder.build(exp.initial).problem
    assert np.all(problem.upper <= 0.01) and "tighter" in problem.upper_by


def test_a_compiled_limit_of_the_wrong_size_is_named() -> None:
    from dualarm_qp.errors import ShapeError
    from dualarm_qp.step.limits import SpeedLimit

    exp = _experiment("puma_beam_limits")
    base = exp.controller().builder
    with pytest.raises(ShapeError, match="the limit 'cap'"):
        StepBuilder(exp.task, base.options, limits=(SpeedLimit("cap", np.ones(3)),))


def test_the_singular_values_are_both_arms_ones() -> None:
    """The kernel computes them when first asked (once per step), as both_arms does."""
    exp = _experiment("panda_pair")
    controller = exp.controller()
    out = controller.step(exp.initial)
    sv = out.sigma_min
    assert out.build.sigma_min == sv == out.build.context.sigma_min
    s = exp.initial
    arms = both_arms(controller.builder.carry, exp.task.follower, s.q_l, s.q_f, s.sigma,
                     s.sigma_leader, exp.task.trajectory.pose(s.t))
    assert sv == arms.sigma_min  # the same values as the kernel's kinematics call


@pytest.mark.parametrize("name", ["puma_beam_limits", "both_sliding_bar",
                                  "curved_bar_waypoints"])
@pytest.mark.parametrize("bad", [math.nan, math.inf, None, "a"])
def test_a_bad_grasp_coordinate_is_a_clear_error(name: str, bad) -> None:
    """Straight grasps too, whose rates the kernel computes without the surface."""
    from dualarm_qp.errors import InvalidInputError, NonFiniteError

    exp = _experiment(name)
    builder = exp.controller().builder
    s0 = exp.initial
    fields = ["sigma"] + (["sigma_leader"] if builder.layout.n_grasp == 2 else [])
    for field in fields:
        values = {"sigma": s0.sigma, "sigma_leader": s0.sigma_leader, field: bad}
        state = DualArmState(s0.t, s0.q_l, s0.q_f, values["sigma"], values["sigma_leader"])
        with pytest.raises((InvalidInputError, NonFiniteError), match=field):
            builder.build(state)


def test_a_plane_bar_with_a_path_of_its_own_is_not_a_line() -> None:
    """A subclass that moves its path is computed from its own point and tangent."""
    from dualarm_qp.task.surfaces import PlaneBar

    class Shifted(PlaneBar):
        def point(self, sigma: float) -> np.ndarray:
            return super().point(sigma) + np.array([0.0, 0.0, 0.05])

    class AsList(PlaneBar):  # a point given as a list of floats
        def point(self, sigma: float):
            return super().point(sigma).tolist()

    assert PlaneBar().line is not None
    for surface in (Shifted(), AsList()):
        assert surface.line is None
        for s in (-0.1, 0.0, 0.2, 0.35, 0.5):
            got = grasp_rates(surface, s, 0.01)
            want = python_era_grasp_rates(surface, s, 0.01)
            assert all(_same_float(g, w) for g, w in zip(got, want, strict=True))


def test_grasp_rate_range_refuses_what_is_not_numbers() -> None:
    from dualarm_qp.errors import InvalidInputError

    good = (np.zeros(3), np.array([0.0, 0.0, 1.0]), np.zeros(3), np.ones(3))
    assert grasp_rate_range(*good, 0.01) == (0.0, 100.0)
    assert grasp_rate_range(*(v.tolist() for v in good), 0.01) == (0.0, 100.0)
    for i in range(4):
        for bad in ([0.0, None, 1.0], [0.0, 1.0], "abc", [[0.0, 0.0, 1.0]]):
            args = list(good)
            args[i] = bad
            with pytest.raises(InvalidInputError, match="3-vector"):
                grasp_rate_range(*args, 0.01)
    for dt in (0.0, -0.01, math.nan, math.inf, "abc", None):
        with pytest.raises(InvalidInputError, match="dt"):
            grasp_rate_range(*good, dt)


@pytest.mark.parametrize("name", ["puma_beam_limits", "both_sliding_bar", "ur5_pair_collision",
                                  "puma_beam_support"])
def test_a_builds_context_reads_its_own_step(name: str) -> None:
    """Read after later steps at other states, a build's context holds the build's
    values (the kernel's arrays of that step; the positions a copy taken at the step)."""
    exp = _experiment(name)
    builder = exp.controller().builder
    rng = np.random.default_rng(3)
    state = _state(exp, builder, rng)
    ref = builder.build(DualArmState(state.t, state.q_l.copy(), state.q_f.copy(),
                                     state.sigma, state.sigma_leader)).context
    ref_surfaces = [surf.pose(state.sigma) for surf in ref.surfaces]
    build = builder.build(state)
    sv = build.sigma_min
    for _ in range(2):  # later steps elsewhere
        builder.build(_state(exp, builder, rng))
    ctx = build.context
    assert ctx.sigma_min == sv
    for field in ("positions", "rate_lo", "rate_hi", "x_applied", "leader_error",
                  "closure_error", "T_f", "J_f"):
        _equal(getattr(ctx, field), getattr(ref, field), field)
    for field in ("T_tool", "J_tool", "T_object", "J_object", "T_target", "J_target"):
        _equal(getattr(ctx.carry, field), getattr(ref.carry, field), field)
    assert ctx.state is state and (ctx.dt, ctx.scale_max) == (ref.dt, ref.scale_max)
    assert len(ctx.surfaces) == len(ref_surfaces)
    for mine, pose in zip(ctx.surfaces, ref_surfaces, strict=True):
        _equal(mine.pose(state.sigma), pose, "a surface")


@pytest.mark.parametrize("name", ["puma_beam_limits", "panda_pair"])
def test_the_kernel_says_whether_a_variable_recovers(name: str) -> None:
    exp = _experiment(name)
    builder = exp.controller().builder
    s0 = exp.initial
    start = builder.build(s0)  # the PUMA beam's starts outside two ranges (the paper's)
    assert start.recovers is bool(start.recovering.any()) is (name == "puma_beam_limits")
    q_f = s0.q_f.copy()
    q_f[1] = exp.task.follower.q_max[1] + 0.01  # past its range: it recovers
    outside = builder.build(dataclasses.replace(s0, q_f=q_f))
    assert outside.recovering[builder.layout.follower][1] and outside.recovers is True
