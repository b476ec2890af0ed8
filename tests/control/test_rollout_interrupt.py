"""A KeyboardInterrupt during a rollout: propagated by default, or a run that stops there.

The command line asks for the stop (``stop_on_interrupt=True``) and writes the samples
done; a library caller (a bench job) gets the exception and nothing half done.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from dualarm_qp.control.controller import DualArmController
from dualarm_qp.control.rollout import rollout
from dualarm_qp.experiments import build_experiment, load_config

CONFIG = Path(__file__).resolve().parents[2] / "configs" / "puma_beam_limits.yaml"
SAMPLES = 30


@pytest.fixture(scope="module")
def exp():
    return build_experiment(load_config(CONFIG))


def _run(exp, **kwargs):
    return rollout(exp.controller(), exp.initial, duration=SAMPLES * exp.options.dt,
                   project=exp.project, limits=exp.limits, **kwargs)


def _interrupt_at(sample: int):
    """A progress callback (called after every sample) that interrupts after ``sample``."""
    calls = [0]

    def progress(path_done: float, time_lost: float) -> None:
        calls[0] += 1
        if calls[0] == sample:
            raise KeyboardInterrupt

    return progress


def test_an_interrupt_propagates_by_default(exp) -> None:
    with pytest.raises(KeyboardInterrupt):
        _run(exp, progress=_interrupt_at(5))


def test_an_interrupt_stops_the_run_with_the_samples_done(exp) -> None:
    whole = _run(exp)
    res = _run(exp, progress=_interrupt_at(5), stop_on_interrupt=True)
    assert res.failure is not None and res.failure.criterion == "interrupted"
    assert "after 5 samples" in res.failure.message
    assert len(res.trace) == 5
    assert res.trace.q_f.tolist() == whole.trace.q_f[:5].tolist()  # the same samples
    assert 0.0 < res.path_completed < whole.path_completed


def test_an_interrupt_before_the_first_sample_leaves_an_empty_run(
        exp, monkeypatch: pytest.MonkeyPatch) -> None:
    def step(self, state, **kwargs):  # type: ignore[no-untyped-def]
        raise KeyboardInterrupt

    monkeypatch.setattr(DualArmController, "step", step)
    res = _run(exp, stop_on_interrupt=True)
    assert len(res.trace) == 0 and res.failure is not None
    assert res.failure.criterion == "interrupted" and res.failure.sample == 0
    assert "after 0 samples" in res.failure.message and res.failure.t == exp.initial.t
    assert res.path_completed == 0.0 and res.time_lost == 0.0
