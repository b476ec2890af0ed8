"""Where one controller step's time goes: the kernel's calls against the Python around them.

For each configuration (default: the PUMA beam, the Panda pair and both grasps sliding),
one rollout's controller inputs are recorded and replayed through a fresh controller,
cycling over them. Every step is timed whole, and inside it the compiled kernel's
calls that the step makes:

* the step in one call (``kernel.StepParts.prepare_solved``: both arms' kinematics, the
  rates to the range ends, the equality, the centres, the compiled limits' boxes and
  rows, the exact solve with its certificate, the look-ahead's bound), which a step with
  the exact solver and no limit of Python's makes; and inside it, by the kernel's own
  clock, its kinematics and its solve with the certificate;
* otherwise the standard parts (``kernel.StepParts.prepare``) and the exact solve with
  its certificate (``kernel.solve_certified``);
* the two calls that replace the solve on a scaled copy of a solved step (a slowed step);
* the look-ahead's prediction (``kernel.predicted_errors``), on the steps that need it.

What is left is Python: the builder, the solver's wrappers, the policy, the
look-ahead's bound, the output objects (and the few other kernel calls a step may make,
such as a slowed step's task-scale LP, which are not split out). A second pass counts
the Python function calls a step makes (``sys.setprofile``; calls into C are counted
apart). The kernel's times
include their arguments' and results' crossing of the binding (timed around the call);
the wrappers that time them add well under a microsecond each.

Run it with ``python benchmarks/step_profile.py [config ...] [--passes 3]`` (about 10 s).
It is a benchmark, not a test: it asserts nothing about speed.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from dualarm_qp._compiled import kernel

sys.path.insert(0, str(Path(__file__).resolve().parent))

# isort: split
from outside_refs import State, experiment, record_states  # the same recorded states

#: The kernel's module-level calls a step makes (timed by wrapping them).
KERNEL_CALLS = {
    "solve_certified": "solve + certificate",
    "solve_nullspace": "solve + certificate",
    "certificate": "solve + certificate",
    "predicted_errors": "look-ahead prediction",
}
PREPARE = "standard parts"
ONE_CALL = "the step in one call"
PARTS = (ONE_CALL, PREPARE, "solve + certificate", "look-ahead prediction")
#: Inside the one call, by the kernel's own clock (not subtracted again from the Python).
INNER = ("  its kinematics", "  its solve + certificate")


class _Clock:
    """The kernel seconds of the step under way, by part."""

    def __init__(self) -> None:
        self.spent: dict[str, float] = dict.fromkeys(PARTS, 0.0)
        self.calls: dict[str, int] = dict.fromkeys(PARTS, 0)
        self.inner: dict[str, float] = dict.fromkeys(INNER, np.nan)

    def reset(self) -> None:
        for part in PARTS:
            self.spent[part] = 0.0
            self.calls[part] = 0
        for part in INNER:
            self.inner[part] = np.nan

    def one_call(self, fn: Callable[..., Any]) -> Callable[..., Any]:
        """``prepare_solved`` timed whole, and its kernel clock's kinematics and solve."""
        timed = self.timed(ONE_CALL, fn)

        def call(*args: Any, **kwargs: Any) -> Any:
            parts, solved = timed(*args, **kwargs)
            self.inner[INNER[0]] = parts[-1]
            self.inner[INNER[1]] = np.nan if solved is None else solved[1]
            return parts, solved
        return call

    def timed(self, part: str, fn: Callable[..., Any]) -> Callable[..., Any]:
        perf = time.perf_counter

        def call(*args: Any, **kwargs: Any) -> Any:
            t0 = perf()
            try:
                return fn(*args, **kwargs)
            finally:
                self.spent[part] += perf() - t0
                self.calls[part] += 1
        return call


class _Parts:
    """The builder's ``kernel.StepParts`` with its ``prepare`` and ``prepare_solved`` timed."""

    def __init__(self, parts: Any, clock: _Clock) -> None:
        self._parts = parts
        self.prepare = clock.timed(PREPARE, parts.prepare)
        self.prepare_solved = clock.one_call(parts.prepare_solved)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._parts, name)


def profile(name: str, passes: int) -> dict[str, Any]:
    """Replay one rollout's states ``passes`` times; the step's split and its call count."""
    exp = experiment(name)
    states, info = record_states(exp)
    ctrl = exp.controller()
    clock = _Clock()
    saved = {attr: getattr(kernel, attr) for attr in KERNEL_CALLS if hasattr(kernel, attr)}
    builder = ctrl.builder
    real_parts = builder._parts
    try:
        for attr, fn in saved.items():
            setattr(kernel, attr, clock.timed(KERNEL_CALLS[attr], fn))
        builder._parts = _Parts(real_parts, clock)
        rows = _timed(ctrl, states, passes, clock)
    finally:
        for attr, fn in saved.items():
            setattr(kernel, attr, fn)
        builder._parts = real_parts
    calls = _counted(ctrl, states)  # without the timing wrappers, which are calls too
    return {"name": name, "states": len(states), "info": info, "rows": rows, **calls}


def _timed(ctrl: Any, states: list[State], passes: int, clock: _Clock
           ) -> dict[str, np.ndarray]:
    perf = time.perf_counter
    total, python = [], []
    parts: dict[str, list[float]] = {part: [] for part in (*PARTS, *INNER)}
    for _ in range(passes):
        ctrl.reset()
        for state, scale_max in states:
            clock.reset()
            t0 = perf()
            ctrl.step(state, scale_max=scale_max)
            t = perf() - t0
            total.append(t)
            python.append(t - sum(clock.spent.values()))
            for part in PARTS:
                # NaN where the step made no such call (the median is over those that did).
                parts[part].append(clock.spent[part] if clock.calls[part] else np.nan)
                if part == ONE_CALL:
                    for inner in INNER:
                        parts[inner].append(clock.inner[inner])
    return {"whole step": np.array(total), **{f"kernel: {p}": np.array(v)
                                              for p, v in parts.items()},
            "Python around them": np.array(python)}


def _counted(ctrl: Any, states: list[State]) -> dict[str, float]:
    """Python function calls and calls into C per step, over one pass."""
    counts = {"call": 0, "c_call": 0}

    def count(frame: Any, event: str, arg: Any) -> None:
        if event in counts:
            counts[event] += 1

    ctrl.reset()
    sys.setprofile(count)
    try:
        for state, scale_max in states:
            ctrl.step(state, scale_max=scale_max)
    finally:
        sys.setprofile(None)
    n = len(states)
    return {"python_calls": counts["call"] / n, "c_calls": counts["c_call"] / n}


def _line(label: str, values: np.ndarray, steps: int) -> str:
    done = values[~np.isnan(values)]
    if done.size == 0:
        return f"  {label:32s} (no call)"
    share = "" if done.size == steps else f"   on {100.0 * done.size / steps:.0f}% of the steps"
    return (f"  {label:32s} median {np.median(done) * 1e6:7.1f} us   "
            f"p99 {np.percentile(done, 99) * 1e6:7.1f} us{share}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("configs", nargs="*",
                        default=["puma_beam_limits", "panda_pair", "both_sliding_bar"])
    parser.add_argument("--passes", type=int, default=3, help="replays of the states")
    args = parser.parse_args(argv)
    for name in args.configs:
        res = profile(name, args.passes)
        rows = res["rows"]
        steps = rows["whole step"].size
        print(f"== {name} ({res['states']} rollout states, {args.passes} passes)")
        for label, values in rows.items():
            print(_line(label, values, steps))
        print(f"  Python function calls per step   {res['python_calls']:.0f} "
              f"(and {res['c_calls']:.0f} calls into C)")
        print()
    return 0


if __name__ == "__main__":
    sys.exit(main())
