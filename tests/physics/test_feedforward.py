"""The plant's load feed-forward: each hand's share through the Jacobian of its own point."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from dualarm_qp.experiments import build_experiment, load_config
from dualarm_qp.physics.plant import MujocoPlant
from dualarm_qp.physics.settings import PhysicsSettings
from dualarm_qp.task.hands import hand_statics, hand_wrenches

pytest.importorskip("mujoco", reason="the physics check needs MuJoCo "
                                     "(pip install -e '.[physics]'; '.[dev]' has it)")

BEAM = Path(__file__).resolve().parents[2] / "configs" / "puma_beam_limits.yaml"


def _virtual_work(arm, q: np.ndarray, point: np.ndarray, wrench: np.ndarray) -> np.ndarray:
    """``tau_j = f . dp/dq_j + m . omega_j`` for the force ``f`` acting at ``point``, a
    point carried by the tool body, and the moment ``m`` (central differences)."""
    T0 = arm.fk(q)
    local = np.linalg.solve(T0, np.r_[point, 1.0])
    _, J = arm.fk_jacobian(q)
    tau = np.empty(q.size)
    h = 1e-6
    for j in range(q.size):
        e = np.zeros(q.size)
        e[j] = h
        dp = ((arm.fk(q + e) @ local)[:3] - (arm.fk(q - e) @ local)[:3]) / (2 * h)
        tau[j] = wrench[:3] @ dp + wrench[3:] @ J[3:, j]
    return tau


def test_the_share_acts_at_the_contact_point_even_off_closure(monkeypatch):
    """The follower's joints 5 mm off its grasp: the split's moment is about the contact
    point on the object, the Jacobian the tool point's; the feed-forward must be the
    torque of the force at the contact point (0.037 N m apart here if the moment is not
    moved to the tool point)."""
    monkeypatch.setattr(MujocoPlant, "_settle", lambda self: None)
    exp = build_experiment(load_config(BEAM), str(BEAM))
    plant = MujocoPlant(exp.task, PhysicsSettings(object_mass=3.0))
    plant.reset(exp.initial, exp.options.dt)
    state = dataclasses.replace(exp.initial, q_f=exp.initial.q_f
                                + np.array([1e-2, -8e-3, 1.2e-2, 0.0, 5e-3, 0.0]))
    plant._feedforward(state)
    task = plant._load_task
    hands, _ = hand_statics(task, state.q_l, state.sigma)
    w = hand_wrenches(task, state.q_l, state.sigma).wrenches
    off = np.linalg.norm(exp.task.follower.fk(state.q_f)[:3, 3] - hands[1].point)
    assert 4e-3 < off < 1e-2, off
    n_l = exp.task.leader.n
    np.testing.assert_allclose(plant._ff[:n_l],
                               _virtual_work(exp.task.leader, state.q_l, hands[0].point, w[0]),
                               atol=1e-6)
    np.testing.assert_allclose(plant._ff[n_l:],
                               _virtual_work(exp.task.follower, state.q_f, hands[1].point, w[1]),
                               atol=1e-6)
