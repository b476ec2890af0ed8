"""The look-ahead's prediction: the errors at the next sample, from one kernel call.

:meth:`Lookahead.predict` moves the joints and the grasps by ``dt x`` and reads the
object's error to ``D(t + scale dt)`` and the grasp's closure error there from one kernel
call (``kernel.predicted_errors``: the moves, then ``kernel.step_errors``, poses only).
Checked here against the same errors computed the long way, from the carried-object
model's poses and the follower's forward kinematics with :func:`pose_error`, and
against the step's own kinematics call at the same state, on the PUMA beam (one sliding
grasp), both grasps sliding (UR5 pair) and a support (Case 2).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dualarm_qp.control.lookahead import Lookahead
from dualarm_qp.errors import InvalidInputError, NonFiniteError, ShapeError
from dualarm_qp.experiments import build_experiment, load_config
from dualarm_qp.se3 import pose_error
from dualarm_qp.step.kinematics import both_arms, both_errors
from dualarm_qp.step.state import DualArmState

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
NAMES = ("puma_beam_limits", "both_sliding_bar", "puma_beam_support")


def setup(name: str) -> tuple:
    path = CONFIGS / f"{name}.yaml"
    exp = build_experiment(load_config(path), str(path))
    ctrl = exp.controller()
    b = ctrl.builder
    return exp, ctrl, Lookahead(exp.task, (1e-3, 1e-3), b.carry, b.n_l, b.n_f)


@pytest.fixture(scope="module", params=NAMES)
def case(request: pytest.FixtureRequest) -> tuple:
    return setup(request.param)


def moved(exp, ctrl, rng: np.random.Generator) -> tuple[DualArmState, np.ndarray]:
    """A state near the start and a random command of the controller's layout."""
    s0 = exp.initial
    q_l = s0.q_l + rng.normal(0.0, 0.05, s0.q_l.shape)
    q_f = s0.q_f + rng.normal(0.0, 0.05, s0.q_f.shape)
    state = DualArmState(float(rng.uniform(0.0, exp.duration)), q_l, q_f,
                         s0.sigma + float(rng.normal(0.0, 0.01)),
                         s0.sigma_leader + (float(rng.normal(0.0, 0.01))
                                            if ctrl.layout.n_grasp == 2 else 0.0))
    return state, rng.normal(0.0, 0.5, ctrl.layout.n)


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), scale=st.floats(0.0, 1.0))
def test_prediction_equals_the_long_way(case: tuple, seed: int, scale: float) -> None:
    exp, ctrl, la = case
    rng = np.random.default_rng(seed)
    state, x = moved(exp, ctrl, rng)
    dt = ctrl.options.dt
    pred = la.predict(state, x, scale, dt)
    n_l, n_f = la.n_l, la.n_f
    q_l = state.q_l + dt * x[:n_l]
    q_f = state.q_f + dt * x[n_l:n_l + n_f]
    sigma = state.sigma + dt * float(x[n_l + n_f])
    sigma_l = state.sigma_leader + (dt * float(x[n_l + n_f + 1]) if x.shape[0] > n_l + n_f + 1
                                    else 0.0)
    kin = ctrl.builder.carry.update(q_l, sigma, sigma_l)
    e_l = pose_error(exp.task.trajectory.pose(state.t + scale * dt), kin.T_object)
    e_c = pose_error(kin.T_target, exp.task.follower.fk(q_f))
    # The kernel's norms (std::hypot) may differ from Python's math.hypot in the last
    # place: equal to a few units of the last place, not to the bit.
    assert pred.tracking == pytest.approx((math.hypot(*e_l[:3]), math.hypot(*e_l[3:])),
                                          rel=1e-15, abs=1e-300)
    assert pred.closure == pytest.approx((math.hypot(*e_c[:3]), math.hypot(*e_c[3:])),
                                         rel=1e-15, abs=1e-300)


def test_the_errors_are_the_step_kinematics_errors(case: tuple) -> None:
    exp, ctrl, _ = case
    rng = np.random.default_rng(7)
    carry, follower = ctrl.builder.carry, exp.task.follower
    for _ in range(20):
        state, _x = moved(exp, ctrl, rng)
        T_D = exp.task.trajectory.pose(state.t)
        e = both_errors(carry, follower, state.q_l, state.q_f, state.sigma,
                        state.sigma_leader, T_D)
        arms = both_arms(carry, follower, state.q_l, state.q_f, state.sigma,
                         state.sigma_leader, T_D)
        assert np.array_equal(e, np.r_[arms.leader_error, arms.closure_error])


def test_a_wrong_joint_vector_is_refused_by_the_kernel() -> None:
    exp, ctrl, _ = setup("puma_beam_limits")
    with pytest.raises(ValueError):
        both_errors(ctrl.builder.carry, exp.task.follower, exp.initial.q_l,
                    exp.initial.q_f[:3], 0.0, 0.0, np.eye(4))


@pytest.mark.parametrize("bad", ["nan rate", "short", "nan state", "short x", "complex x",
                                 "text x", "text sigma", "nan sigma_leader"])
def test_a_bad_prediction_input_is_a_clear_error(bad: str) -> None:
    exp, ctrl, la = setup("puma_beam_limits")
    state, x = moved(exp, ctrl, np.random.default_rng(1))
    s = state
    error: type[Exception] = NonFiniteError
    if bad == "nan rate":
        x[la.n_l + 2] = np.nan
    elif bad == "short":
        state = DualArmState(s.t, s.q_l, s.q_f[:4], s.sigma)
        error = ShapeError
    elif bad == "nan state":
        state = DualArmState(s.t, s.q_l, s.q_f, np.nan)
    elif bad == "short x":
        x, error = x[:-1], ShapeError
    elif bad == "complex x":
        x, error = x + 1j, InvalidInputError
    elif bad == "text x":
        x, error = ["a"] * x.shape[0], InvalidInputError
    elif bad == "text sigma":
        state, error = DualArmState(s.t, s.q_l, s.q_f, "a"), InvalidInputError
    else:  # a rigid leader's grasp coordinate is checked too, as the controller does
        state = DualArmState(s.t, s.q_l, s.q_f, s.sigma, np.nan)
    with pytest.raises(error):
        la.predict(state, x, 1.0, ctrl.options.dt)


def test_a_prediction_takes_what_the_controller_takes() -> None:
    """A list, a float32 array and a NumPy float state: the same numbers as float64."""
    exp, ctrl, la = setup("both_sliding_bar")
    state, x = moved(exp, ctrl, np.random.default_rng(4))
    x = x.astype(np.float32).astype(np.float64)  # representable in float32
    dt = ctrl.options.dt
    ref = la.predict(state, x, 0.5, dt)
    same = DualArmState(state.t, list(state.q_l), state.q_f, np.float64(state.sigma),
                        np.float64(state.sigma_leader))
    for command in (list(x), x.astype(np.float32)):
        assert la.predict(same, command, 0.5, dt) == ref


def test_the_kernel_refuses_a_command_of_another_layout() -> None:
    """``kernel.predicted_errors`` names what it takes instead of reading past an array."""
    from dualarm_qp._compiled import kernel

    exp, ctrl, _ = setup("puma_beam_limits")
    state, x = moved(exp, ctrl, np.random.default_rng(2))
    carry, follower = ctrl.builder.carry, exp.task.follower
    args = dict(carry=carry.chain, carry_frames=carry.frames, follower=follower.chain,
                follower_tool=follower.tool_frame_id, q_l=state.q_l, q_f=state.q_f,
                sigma_f=state.sigma, sigma_l=0.0, x=x, col_rate=carry.columns[1], dt=0.01,
                T_D=np.eye(4))
    assert kernel.predicted_errors(**args).finite
    for key, bad in (("x", np.r_[x, 0.0, 0.0]), ("x", x[:-2]), ("q_f", state.q_f[:5]),
                     ("col_rate", carry.columns[1][:-1])):
        with pytest.raises(ValueError, match="predicted_errors"):
            kernel.predicted_errors(**{**args, key: bad})
    x_nan = x.copy()
    x_nan[0] = np.nan
    out = kernel.predicted_errors(**{**args, "x": x_nan})
    assert not out.finite
    assert (out.tracking_position, out.tracking_rotation, out.closure_position,
            out.closure_rotation) == (0.0, 0.0, 0.0, 0.0)


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), share=st.sampled_from([0.3, 0.9, 0.999, 1.001, 1.1, 3.0]))
def test_the_bound_is_the_module_docstrings(case: tuple, seed: int, share: float) -> None:
    """``Lookahead.negligible`` (one kernel call) against the bound written here in Python:
    the turns' squares times the chains' lengths (the leader's plus the lever from its
    tool to the follower's target) and the grasps' travel, against a tenth of the budget.
    The bound is quadratic in the command: each command is scaled to ``share`` times the
    threshold, on both sides of it."""
    from dualarm_qp.control.lookahead import SKIP_SHARE, chain_length

    exp, ctrl, la = case
    rng = np.random.default_rng(seed)
    state, x = moved(exp, ctrl, rng)
    build = ctrl.builder.build(state)
    dt, n_l, n_f = ctrl.options.dt, la.n_l, la.n_f
    lever = np.linalg.norm(build.carry.T_target[:3, 3] - build.carry.T_tool[:3, 3])
    lengths = chain_length(exp.task.leader) + lever, chain_length(exp.task.follower)

    def shares(x: np.ndarray) -> tuple[float, float]:
        a, b = dt * np.abs(x[:n_l]).sum(), dt * np.abs(x[n_l:n_l + n_f]).sum()
        g = dt * np.abs(x[n_l + n_f:]).sum()
        pos = 0.5 * (a**2 * lengths[0] + b**2 * lengths[1]) + 0.5 * g**2 + a * g
        rot = 0.5 * (a**2 + b**2)
        return pos / (SKIP_SHARE * la.budget[0]), rot / (SKIP_SHARE * la.budget[1])

    x = x * math.sqrt(share / max(shares(x)))
    assert max(shares(x)) == pytest.approx(share, rel=1e-9)
    assert la.negligible(build, x, dt) == (share < 1.0)
