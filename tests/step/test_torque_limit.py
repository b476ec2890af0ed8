"""The torque limit's rows: ``|tau + dt D x| <= tau_max``, stacked only when asked for."""

from __future__ import annotations

import dataclasses
import pickle
from pathlib import Path

import numpy as np
import pytest
import yaml

from dualarm_qp._compiled import kernel
from dualarm_qp.cli import main
from dualarm_qp.errors import InvalidInputError, ShapeError
from dualarm_qp.experiments import build_experiment, parse_config
from dualarm_qp.kinematics.robots import example_robots_dir
from dualarm_qp.step.build import StepBuilder
from dualarm_qp.step.limits.torque import ROW_PREFIX, SupportTorqueLimit, TorqueLimit
from dualarm_qp.step.state import DualArmState
from dualarm_qp.task.torques import LoadTorques

CONFIGS = Path(__file__).resolve().parents[2] / "configs"


def _puma(**controller: object) -> dict:
    data = yaml.safe_load((CONFIGS / "puma_beam_limits.yaml").read_text())
    data["object"].update(mass=6.0, mass_centre=[0.0, 0.0, 250.0])
    data["controller"].update(controller)
    return data


def _experiment(tau_max: list[float] | None = None, **controller: object):
    data = _puma(**controller)
    if tau_max is not None:
        data["leader"]["tau_max"] = tau_max
        data["follower"]["tau_max"] = tau_max
    return build_experiment(parse_config(data), "puma_beam_limits")


def test_rows_are_the_linearised_torques() -> None:
    limits = [200.0, 80.0, 60.0, np.inf, 15.0, 10.0]
    exp = _experiment(limits, torque_limits=True)
    builder = StepBuilder(exp.task, exp.options)
    assert "torque" in builder.row_limits
    build = builder.build(exp.initial)
    p = build.problem
    rows = [i for i, name in enumerate(p.row_names) if name.startswith(ROW_PREFIX)]
    # Five limited joints per arm, two rows each.
    assert len(rows) == 20
    assert p.row_names[rows[0]] == "torque ql1 max" and p.row_names[rows[-1]] == "torque qf6 min"
    s = exp.initial
    st = LoadTorques(exp.task).linearised(s.q_l, s.q_f, s.sigma)
    lim = np.r_[limits, limits]
    keep = np.isfinite(lim)
    G, h = p.G[rows], p.h[rows]
    dt = exp.options.dt
    np.testing.assert_allclose(G[:10], dt * st.D[keep], atol=1e-12)
    np.testing.assert_allclose(G[10:], -dt * st.D[keep], atol=1e-12)
    np.testing.assert_allclose(h[:10], lim[keep] - st.tau[keep], atol=1e-12)
    np.testing.assert_allclose(h[10:], lim[keep] + st.tau[keep], atol=1e-12)
    # The rows predict the next sample's torques to first order: the rest is second
    # order in the step (a quarter for half the rates). These rates move the follower's
    # tool point off its contact point by millimetres (the torques count the moment of
    # that offset): 8 mN m; a rate that keeps the step's equality leaves 0.01 mN m.
    rest = []
    for x in (np.linspace(-0.3, 0.3, p.n), np.linspace(-0.15, 0.15, p.n)):
        y = np.r_[s.q_l, s.q_f, s.sigma] + dt * x
        t1 = LoadTorques(exp.task).torques(y[:6], y[6:12], float(y[12]))
        rest.append(np.abs(t1 - (st.tau + dt * st.D @ x)).max())
    assert rest[0] < 1e-2 and rest[1] < 0.3 * rest[0], rest
    x = np.linalg.lstsq(p.A, p.b, rcond=None)[0]  # a rate that keeps A x = b
    y = np.r_[s.q_l, s.q_f, s.sigma] + dt * x
    t1 = LoadTorques(exp.task).torques(y[:6], y[6:12], float(y[12]))
    assert np.abs(t1 - (st.tau + dt * st.D @ x)).max() < 5e-4


def _at_start(limits: list[float]):
    """The experiment with these torque limits, its first step's context and layout, its
    load torques and their linearisation at the start."""
    exp = _experiment(limits, torque_limits=True)
    builder = StepBuilder(exp.task, exp.options)
    ctx = builder.build(exp.initial).context
    torques = LoadTorques(exp.task)
    st = torques.linearised(ctx.state.q_l, ctx.state.q_f, ctx.state.sigma)
    return exp, ctx, builder.layout, torques, st


def test_every_joint_limited_gives_the_same_rows_as_a_selection() -> None:
    """Every joint limited (the rows taken whole) and one joint less (a selection)."""
    every = [200.0, 80.0, 60.0, 40.0, 15.0, 10.0]
    exp, ctx, lay, torques, st = _at_start(every)
    dt = exp.options.dt
    for limits in (every, [200.0, 80.0, 60.0, np.inf, 15.0, 10.0]):
        lim = np.r_[limits, limits]
        keep = np.flatnonzero(np.isfinite(lim))
        c = TorqueLimit(torques, lim, lay).constraint(ctx)
        assert c.G is not None and c.h is not None
        assert c.G.flags.c_contiguous and c.G.shape == (2 * keep.size, lay.n)
        np.testing.assert_array_equal(c.G, np.vstack([dt * st.D[keep], -(dt * st.D[keep])]))
        np.testing.assert_array_equal(c.h, np.r_[lim[keep] - st.tau[keep],
                                                 lim[keep] + st.tau[keep]])


def test_limits_of_the_wrong_length_are_refused() -> None:
    exp = _experiment([200.0, 80.0, 60.0, 40.0, 15.0, 10.0], torque_limits=True)
    lay = StepBuilder(exp.task, exp.options).layout
    with pytest.raises(ShapeError, match="tau_max"):
        TorqueLimit(LoadTorques(exp.task), np.full(3, 10.0), lay)
    with pytest.raises(ShapeError, match="tau_max"):
        TorqueLimit(LoadTorques(exp.task), np.float64(10.0), lay)


def test_no_rows_when_off_and_no_leader_rows_without_leader_limits() -> None:
    exp = _experiment([100.0] * 6)
    assert "torque" not in StepBuilder(exp.task, exp.options).row_limits
    on = dataclasses.replace(exp.options, torque_limits=True)
    limit = next(lim for lim in StepBuilder(exp.task, on, leader_bounds=False).limits
                 if isinstance(lim, TorqueLimit))
    assert all(" qf" in name for name in limit.row_names)


def test_a_binding_row_is_met_with_equality() -> None:
    """A limit just below the start's torque: the step's answer lies on its row."""
    exp = _experiment(None, torque_limits=False)
    s = exp.initial
    tau = LoadTorques(exp.task).torques(s.q_l, s.q_f, s.sigma)
    limits = np.full(12, np.inf)
    limits[7] = abs(tau[7]) + 0.01  # the follower's shoulder: 10 mN m of room
    opts = dataclasses.replace(exp.options, torque_limits=True,
                               leader_tau_max=limits[:6], follower_tau_max=limits[6:])
    exp = dataclasses.replace(exp, options=opts)
    controller = exp.controller()
    out = controller.step(s)
    p = out.build.problem
    names = p.row_names
    gap = p.G @ out.solution.x - p.h
    side = "max" if tau[7] > 0 else "min"
    j = names.index(f"torque qf2 {side}")
    assert gap.max() <= 1e-7
    assert gap[j] > -1e-6  # active


def test_a_dh_arm_must_state_its_limits(tmp_path: Path,
                                        capsys: pytest.CaptureFixture[str]) -> None:
    cfg = tmp_path / "puma.yaml"
    cfg.write_text(yaml.safe_dump(_puma(torque_limits=True)))
    code = main(["run", str(cfg), "--out", str(tmp_path / "out"), "--no-plots", "--quiet"])
    err = capsys.readouterr().err
    assert code == 2, err
    assert "leader.tau_max" in err and "puma.yaml" in err
    with pytest.raises(InvalidInputError, match="give tau_max"):
        StepBuilder(_experiment().task, dataclasses.replace(_experiment().options,
                                                            torque_limits=True))


def test_an_approach_time_closes_a_share_of_each_margin_per_sample() -> None:
    """``torque_approach`` T: a joint inside its limit may close ``dt / T`` of its margin
    in one sample; a joint beyond it is still asked back in one sample."""
    every = [200.0, 80.0, 60.0, 40.0, 15.0, 10.0]
    exp, ctx, lay, torques, st = _at_start(every)
    dt = exp.options.dt
    lim = np.r_[every, every]
    lim[7] = 0.5 * abs(st.tau[7])  # the follower's joint 2 already beyond its limit
    margin = np.r_[lim - st.tau, lim + st.tau]
    assert (margin < 0).sum() == 1
    for approach, share in ((0.2, dt / 0.2), (0.5 * dt, 1.0)):
        c = TorqueLimit(torques, lim, lay, approach).constraint(ctx)
        np.testing.assert_allclose(c.h, np.where(margin > 0, share * margin, margin),
                                   rtol=1e-12)
    with pytest.raises(InvalidInputError, match="torque_approach"):
        dataclasses.replace(exp.options, torque_approach=0.0)


#: Configs with a load (mass [kg], mass centre [mm]; None: as configured) for the compiled
#: rows: a rigid leader grasp, both grasps sliding, a curved path (a revolute grasp joint).
LOADS = {"puma_beam_limits": (6.0, [0.0, 0.0, 250.0]),
         "both_sliding_bar": (4.0, [0.0, 0.0, 400.0]),
         "curved_bar_waypoints": (5.0, [0.0, 0.0, 200.0]),
         "ur5_pair_heavy_bar": (None, None)}


@pytest.mark.parametrize("loaded", [True, False])
@pytest.mark.parametrize("name", list(LOADS))
def test_the_compiled_rows_are_the_python_statics(name: str, loaded: bool) -> None:
    """At random states the compiled limit's rows are those of LoadTorques.linearised.

    The torques and the joints' columns to rounding; the grasps' columns (forward
    differences over GRASP_STEP, 1e-7 m, whose rounding is about 1e-9 of their size) to
    1e-7 of the largest entry; with no load bit for bit (the same kernel statics)."""
    if name.startswith(("ur5", "both")) and example_robots_dir() is None:
        pytest.skip("example-robot-data is not installed")
    data = yaml.safe_load((CONFIGS / f"{name}.yaml").read_text())
    mass, centre = LOADS[name]
    if not loaded:
        data["object"].pop("mass", None)
        data["object"].pop("mass_centre", None)
    elif mass is not None:
        data["object"].update(mass=mass, mass_centre=centre)
    exp = build_experiment(parse_config(data), name)
    assert (exp.task.load is not None) == loaded
    builder = StepBuilder(exp.task, exp.options)
    lay = builder.layout
    torques = LoadTorques(exp.task)
    lim = np.full(lay.n_l + lay.n_f, 500.0)
    limit = TorqueLimit(torques, lim, lay)
    assert type(limit).constraint is kernel.TorqueLimit.constraint  # compiled, not Python
    copy = pickle.loads(pickle.dumps(limit))
    rng = np.random.default_rng(7)
    s0, joints = exp.initial, lay.n_l + lay.n_f
    for _ in range(8):
        s = DualArmState(0.0, s0.q_l + rng.normal(0.0, 0.1, lay.n_l),
                         s0.q_f + rng.normal(0.0, 0.1, lay.n_f),
                         s0.sigma + float(rng.normal(0.0, 0.01)),
                         s0.sigma_leader + float(rng.normal(0.0, 0.01)) * (lay.n_grasp - 1))
        ctx = builder.build(s).context
        c = limit.constraint(ctx)
        st = torques.linearised(s.q_l, s.q_f, s.sigma, s.sigma_leader)
        G, h = ctx.dt * st.D, np.r_[lim - st.tau, lim + st.tau]
        assert c.row_names == limit.row_names and c.G.shape == (2 * joints, lay.n)
        np.testing.assert_array_equal(c.G[joints:], -c.G[:joints])
        scale = np.abs(G).max()
        if loaded:
            np.testing.assert_allclose(c.h, h, rtol=0.0, atol=1e-12 * np.abs(h).max())
            np.testing.assert_allclose(c.G[:joints, :joints], G[:, :joints], rtol=0.0,
                                       atol=1e-13 * scale)
            np.testing.assert_allclose(c.G[:joints, joints:], G[:, joints:], rtol=0.0,
                                       atol=1e-7 * scale)
            assert np.abs(G[:, joints:]).max() > 1e-3 * scale  # the grasps move the split
        else:
            np.testing.assert_array_equal(c.h, h)
            np.testing.assert_array_equal(c.G[:joints], G)
        copied = copy.constraint(ctx)
        np.testing.assert_array_equal(copied.G, c.G)
        np.testing.assert_array_equal(copied.h, c.h)


def test_a_supported_load_has_the_python_rows() -> None:
    """A follower that supports the load (Case 2): the rows are LoadTorques.linearised's,
    asked in Python; the compiled limit refuses such a task."""
    data = yaml.safe_load((CONFIGS / "puma_beam_support.yaml").read_text())
    data["leader"]["tau_max"] = data["follower"]["tau_max"] = [300.0] * 6
    data["controller"]["torque_limits"] = True
    exp = build_experiment(parse_config(data), "puma_beam_support")
    builder = StepBuilder(exp.task, exp.options)
    limit = next(lim for lim in builder.limits if lim.name == "torque")
    assert isinstance(limit, SupportTorqueLimit)
    s = exp.initial
    p = builder.build(s).problem
    st = LoadTorques(exp.task).linearised(s.q_l, s.q_f, s.sigma)
    rows = [i for i, name in enumerate(p.row_names) if name.startswith(ROW_PREFIX)]
    np.testing.assert_array_equal(p.G[rows[:12]], exp.options.dt * st.D)
    np.testing.assert_array_equal(p.h[rows[:12]], 300.0 - st.tau)
    with pytest.raises(InvalidInputError, match="SupportTorqueLimit"):
        TorqueLimit(LoadTorques(exp.task), np.full(12, 300.0), builder.layout)
