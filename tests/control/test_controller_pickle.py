"""A controller pickles and copies whole: its copy steps as it does.

The objects it holds that a pickle cannot (the kernel's: the builder's parts, the arms'
chains, the collision scene's coal solvers, the statics' chains; a native QP solver's
module and set-up solver) are left out and made again
(:class:`~dualarm_qp._remade.KernelHolder`). A fresh controller's copy steps bit for bit
as the controller. A copy taken mid-run carries the run's memory (the last command, for
the acceleration limits and the warm start) and steps the same, bit for bit, except
with the iterative QP solvers that keep state of their own between steps (osqp's step
size and duals, proxqp's), which start afresh in the copy: there the answers agree to
the solvers' tolerance.
"""

from __future__ import annotations

import copy
import pickle
from pathlib import Path

import numpy as np
import pytest

from dualarm_qp.errors import PairingError
from dualarm_qp.experiments import build_experiment, load_config
from dualarm_qp.kinematics.robots import example_robots_dir
from dualarm_qp.solvers import available_solvers
from tests.control.test_controller_verify import stepped

CONFIGS = Path(__file__).resolve().parents[2] / "configs"

#: The solvers whose own state carries from one step to the next.
STATEFUL = ("qp:osqp", "qp:proxsuite")


def _steps(controller, state) -> list:
    return stepped(controller, state, 10)


def _same(one: list, two: list, atol: float = 0.0) -> None:
    for a, b in zip(one, two, strict=True):
        assert a.status is b.status
        for name in ("ql_dot", "qf_dot"):
            np.testing.assert_allclose(getattr(a, name), getattr(b, name), rtol=0.0,
                                       atol=atol)
        np.testing.assert_allclose([a.m, a.m_leader, a.scale], [b.m, b.m_leader, b.scale],
                                   rtol=0.0, atol=atol)
        assert a.build.problem.row_names == b.build.problem.row_names


@pytest.mark.parametrize("solver", available_solvers())
@pytest.mark.parametrize("config", [
    "puma_beam_limits", "puma_beam_pillar",  # the standard parts; collision rows, a box
    pytest.param("ur5_pair_heavy_bar", marks=pytest.mark.skipif(  # torque rows
        example_robots_dir() is None, reason="example-robot-data is not installed"))])
def test_a_pickled_controller_steps_as_the_original(config: str, solver: str) -> None:
    path = CONFIGS / f"{config}.yaml"
    try:
        exp = build_experiment(load_config(path), path, solver=solver)
    except PairingError:
        pytest.skip(f"{solver} does not take {config}'s limits")
    expected = _steps(exp.controller(), exp.initial)
    _same(_steps(pickle.loads(pickle.dumps(exp.controller())), exp.initial), expected)
    _same(_steps(copy.deepcopy(exp.controller()), exp.initial), expected)
    mid = exp.controller()
    state = exp.initial
    for _ in range(5):
        state = state.advanced(mid.step(state), mid.options.dt)
    twin = pickle.loads(pickle.dumps(mid))
    _same(_steps(twin, state), _steps(mid, state), atol=1e-5 if solver in STATEFUL else 0.0)
