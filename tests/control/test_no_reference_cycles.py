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
import types
from pathlib import Path

import pytest

from dualarm_qp.control.rollout import rollout
from dualarm_qp.experiments import build_experiment, load_config

CONFIGS = Path(__file__).resolve().parents[2] / "configs"


def _ours(obj: object) -> bool:
    """Whether ``obj`` is one of the library's objects or a frame of its code."""
    if isinstance(obj, types.FrameType):
        return "dualarm_qp" in obj.f_code.co_filename
    return type(obj).__module__.startswith("dualarm_qp")


@pytest.mark.parametrize("name", ["puma_beam_limits", "panda_pair", "ur5_pair_collision",
                                  "ur5_pair_heavy_bar"])
def test_a_rollout_leaves_no_cyclic_garbage(name):
    path = CONFIGS / f"{name}.yaml"
    exp = build_experiment(load_config(path), str(path))
    duration = min(exp.duration, 1.0)
    # A first rollout does the one-time work (modules imported on first use, caches
    # filled), which may well leave cycles of its own.
    rollout(exp.controller(), exp.initial, duration=duration, limits=exp.limits)
    controller = exp.controller()
    gc.collect()
    gc.disable()
    gc.set_debug(gc.DEBUG_SAVEALL)  # what the collection finds is kept in gc.garbage
    try:
        result = rollout(controller, exp.initial, duration=duration, limits=exp.limits)
        gc.collect()
        # Garbage of other tests' objects may be freed meanwhile (a figure of an earlier
        # test, say): what counts is that none of it is the library's.
        ours = [type(obj).__name__ for obj in gc.garbage if _ours(obj)]
    finally:
        gc.set_debug(0)
        gc.garbage.clear()
        gc.enable()
    assert len(result.trace) > 10
    assert ours == []
