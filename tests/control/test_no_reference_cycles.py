"""A step and a rollout leave no reference cycles: their garbage is freed at once.

Objects in a reference cycle wait for Python's cyclic garbage collector, whose pauses
grow with what it has to scan (tens of milliseconds were measured in the 1 kHz loop of
``examples/realtime_loop.py`` while every step's problem formed a cycle with its cached
inequalities). Here a whole rollout runs with the collector off and the collection
after it must find nothing: on the PUMA beam, on the Panda pair (whose path slows
steps through the scale policy) and with collision and torque rows.
"""

from __future__ import annotations

import gc
from pathlib import Path

import pytest

from dualarm_qp.control.rollout import rollout
from dualarm_qp.experiments import build_experiment, load_config

CONFIGS = Path(__file__).resolve().parents[2] / "configs"


@pytest.mark.parametrize("name", ["puma_beam_limits", "panda_pair", "ur5_pair_collision",
                                  "ur5_pair_heavy_bar"])
def test_a_rollout_leaves_no_cyclic_garbage(name):
    path = CONFIGS / f"{name}.yaml"
    exp = build_experiment(load_config(path), str(path))
    controller = exp.controller()
    gc.collect()
    gc.disable()
    try:
        result = rollout(controller, exp.initial, duration=min(exp.duration, 1.0),
                         limits=exp.limits)
        found = gc.collect()
    finally:
        gc.enable()
    assert len(result.trace) > 10
    assert found == 0
