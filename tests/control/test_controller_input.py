"""The controller used on its own: measured states are checked, not trusted."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from dualarm_qp.errors import DualArmError, NonFiniteError, ShapeError
from dualarm_qp.experiments import build_experiment, load_config
from dualarm_qp.step.state import DualArmState

CONFIG = Path(__file__).resolve().parents[2] / "configs" / "puma_beam_sliding_s7_100.yaml"


@pytest.fixture(scope="module")
def exp():
    return build_experiment(load_config(CONFIG), solver="nullspace")


def test_plain_lists_are_accepted(exp):
    st = exp.initial
    out = exp.controller().step(DualArmState(0, list(st.q_l), st.q_f.tolist(), 0.45))
    ref = exp.controller().step(st)
    np.testing.assert_array_equal(out.qf_dot, ref.qf_dot)
    assert out.m == ref.m


@pytest.mark.parametrize(("q_l", "q_f", "sigma", "error", "text"), [
    (np.zeros(5), None, 0.45, ShapeError, "leader joints q_l"),
    (None, np.zeros(7), 0.45, ShapeError, "follower joints q_f"),
    (None, np.full(6, np.nan), 0.45, NonFiniteError, "follower joints q_f"),
    (None, None, float("nan"), NonFiniteError, "sigma"),
    (None, ["a"] * 6, 0.45, DualArmError, "follower joints q_f"),
])
def test_bad_states_raise_clear_errors(exp, q_l, q_f, sigma, error, text):
    st = exp.initial
    bad = DualArmState(0.0, st.q_l if q_l is None else q_l, st.q_f if q_f is None else q_f,
                       sigma)
    with pytest.raises(error, match=text):
        exp.controller().step(bad)


def test_advanced_state_is_the_euler_step_of_the_command():
    from types import SimpleNamespace

    s = DualArmState(1.0, np.zeros(6), np.ones(6), 0.2, 0.1)
    cmd = SimpleNamespace(ql_dot=np.full(6, 2.0), qf_dot=np.full(6, -1.0), m=0.5,
                          m_leader=-0.25, scale=0.5)
    n = s.advanced(cmd, 0.1)
    assert n.t == pytest.approx(1.05)
    np.testing.assert_allclose(n.q_l, 0.2)
    np.testing.assert_allclose(n.q_f, 0.9)
    assert n.sigma == pytest.approx(0.25) and n.sigma_leader == pytest.approx(0.075)
    assert s.t == 1.0 and s.q_l[0] == 0.0  # the state itself is not changed
