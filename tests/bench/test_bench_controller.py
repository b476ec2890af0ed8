"""The bench job, the canonical steps and the suite generator build their controller
through Experiment.controller, without the fallback solver."""

from __future__ import annotations

import importlib.util
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np
import pytest
import yaml

from dualarm_qp.bench import BenchSettings, run_job, runner
from dualarm_qp.control.controller import DualArmController
from dualarm_qp.experiments.config import parse_config
from dualarm_qp.experiments.setup import Experiment, build_experiment
from dualarm_qp.solvers.base import Tolerance

ROOT = Path(__file__).resolve().parents[2]
LIMITS = str(ROOT / "configs" / "puma_beam_limits.yaml")


class Spy:
    """Experiment.controller, recording each call's keywords and the controller built."""

    def __init__(self) -> None:
        self.calls: list[tuple[dict[str, Any], DualArmController]] = []
        self._original = Experiment.controller

    def method(self) -> Any:
        """A function to set as Experiment.controller (bound like the original)."""

        def controller(exp: Experiment, **kw: Any) -> DualArmController:
            ctrl = self._original(exp, **kw)
            self.calls.append((kw, ctrl))
            return ctrl

        return controller


@pytest.fixture
def spy(monkeypatch: pytest.MonkeyPatch) -> Spy:
    s = Spy()
    monkeypatch.setattr(Experiment, "controller", s.method())
    return s


def _make_suite() -> ModuleType:
    spec = importlib.util.spec_from_file_location("make_suite",
                                                  ROOT / "benchmarks" / "make_suite.py")
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_bench_job_and_canonical_steps_use_the_experiment_controller(spy: Spy) -> None:
    tol = Tolerance(equality=2e-7, bounds=2e-7)  # looser than the default: all pass
    settings = BenchSettings(duration=0.124, tolerance=tol, repeat=2)
    rec = run_job(runner.read_config(LIMITS), "qp:daqp", settings)
    # Two repeats of the job and one rollout for the canonical steps (replay).
    assert len(spy.calls) == 3
    assert rec["success_rate"] == 1.0 and rec["replay_steps"] == rec["steps"] > 1
    solvers = sorted(ctrl.solver.name for _, ctrl in spy.calls)
    assert solvers == ["nullspace", "qp:daqp", "qp:daqp"]
    for kw, ctrl in spy.calls:
        # Each backend's own success: the configured fallback (nullspace) is left out.
        assert kw["fallback"] is False and ctrl.fallback is None
        assert kw["tolerance"] == tol and ctrl.tolerance == tol
        assert ctrl.on_step is not None
    spy.calls.clear()
    steps = runner.canonical_steps(runner.read_config(LIMITS), settings)
    assert len(spy.calls) == 1 and len(steps) == rec["steps"]


def test_the_configured_fallback_is_kept_outside_the_bench() -> None:
    exp = build_experiment(parse_config(yaml.safe_load(Path(LIMITS).read_text()), LIMITS),
                           LIMITS, solver="qp:daqp")
    assert exp.controller().fallback is not None
    assert exp.controller(fallback=False).fallback is None


def test_suite_generator_uses_the_experiment_controller_and_the_configs_units(
        spy: Spy) -> None:
    mod = _make_suite()
    base = yaml.safe_load(mod.BASE_CONFIG.read_text(encoding="utf-8"))
    assert base["controller"]["weights"]["grasp_unit"] == "m"
    cfg = mod.scenario(np.random.default_rng(mod.SEED), base, 0)
    problems = mod.record(cfg)
    assert len(spy.calls) == 1
    kw, ctrl = spy.calls[0]
    assert kw["fallback"] is False and ctrl.on_step is not None
    assert len(problems) > 2
    # s7 is the file's number in the shipped configs' unit (grasp_unit: m, i.e. SI).
    s7 = cfg["controller"]["weights"]["grasp"]
    assert s7 in (1.0, 100.0, 1000.0)
    assert ctrl.options.grasp_weight == pytest.approx(s7)
    np.testing.assert_allclose([p.weights[-1] for p in problems], s7, rtol=1e-12)
