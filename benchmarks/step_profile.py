"""Where one controller step's time goes: the kernel's calls against the Python around them.

For each configuration (default: the PUMA beam, the Panda pair and both grasps sliding),
one rollout's controller inputs are recorded and replayed through a fresh controller,
cycling over them. Every step is timed whole, and inside it the compiled kernel's
calls that the step makes:

* the step's one loop (``kernel.Step.build``: both arms' kinematics, every task, cost
  term and limit asked in turn, their pieces stacked); and inside it, by the kernel's
  own clock, its kinematics;
* the exact solve with its certificate (``kernel.solve_certified``, or the calls one by
  one on a scaled copy of a slowed step);
* the look-ahead's bound (``kernel.negligible``) and prediction
  (``kernel.predicted_errors``), on the steps that need them.

What is left is Python: the builder, the solver's wrappers, the policy, the output
objects (and the few other kernel calls a step may make, such as a slowed step's
task-scale LP, which are not split out). A second pass counts the Python function calls
a step makes (``sys.setprofile``; calls into C are counted apart). The kernel's times
include their arguments' and results' crossing of the binding (timed around the call);
the wrappers that time them add well under a microsecond each.

``--parts`` measures the door a part goes through, on the PUMA beam's states, each
variant timed interleaved with the standard step: a limit written in Python that gives
nothing (what the kernel's call back into Python costs), and the standard limits asked
one by one from Python with ``limit.constraint(ctx)`` (what a loop in Python would
cross instead of the kernel's loop).

Run it with ``python benchmarks/step_profile.py [config ...] [--passes 3] [--parts]``
(about 10 s). It is a benchmark, not a test: it asserts nothing about speed.
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
    "negligible": "look-ahead",
    "predicted_errors": "look-ahead",
}
LOOP = "the step's loop"
PARTS = (LOOP, "solve + certificate", "look-ahead")
#: Inside the loop, by the kernel's own clock (not subtracted again from the Python).
INNER = ("  its kinematics",)


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

    def loop(self, fn: Callable[..., Any]) -> Callable[..., Any]:
        """``Step.build`` timed whole, and its kernel clock's kinematics."""
        timed = self.timed(LOOP, fn)

        def call(out: Any, *args: Any, **kwargs: Any) -> Any:
            timed(out, *args, **kwargs)
            self.inner[INNER[0]] = out.kinematics_seconds
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


class _Step:
    """The builder's ``kernel.Step`` with its ``build`` timed."""

    def __init__(self, step: Any, clock: _Clock) -> None:
        self._step = step
        self.build = clock.loop(step.build)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._step, name)


def profile(name: str, passes: int) -> dict[str, Any]:
    """Replay one rollout's states ``passes`` times; the step's split and its call count."""
    exp = experiment(name)
    states, info = record_states(exp)
    ctrl = exp.controller()
    clock = _Clock()
    saved = {attr: getattr(kernel, attr) for attr in KERNEL_CALLS if hasattr(kernel, attr)}
    builder = ctrl.builder
    real_step = builder._step
    try:
        for attr, fn in saved.items():
            setattr(kernel, attr, clock.timed(KERNEL_CALLS[attr], fn))
        builder._step = _Step(real_step, clock)
        rows = _timed(ctrl, states, passes, clock)
    finally:
        for attr, fn in saved.items():
            setattr(kernel, attr, fn)
        builder._step = real_step
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
                if part == LOOP:
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


class _Nothing:
    """A limit written in Python that gives nothing: the door's own cost."""

    name = "nothing"
    gives_rows = False

    def constraint(self, ctx: Any) -> Any:
        return kernel.Constraint()


def parts(passes: int) -> None:
    """The door a part goes through (see the module docstring)."""
    from dualarm_qp.step.build import StepBuilder

    exp = experiment("puma_beam_limits")
    states, _ = record_states(exp)
    standard = StepBuilder(exp.task, exp.options)
    with_python = StepBuilder(exp.task, exp.options, limits=[_Nothing()])
    perf = time.perf_counter
    base, door, one_by_one = [], [], []
    for _ in range(passes):
        for state, scale_max in states:
            t0 = perf()
            build = standard.build(state, scale_max=scale_max)
            t1 = perf()
            with_python.build(state, scale_max=scale_max)
            t2 = perf()
            ctx = build.context
            for limit in standard.limits:
                limit.constraint(ctx)
            for task in standard.tasks:
                task.equality(ctx)
            standard.cost.quadratic(ctx)
            t3 = perf()
            base.append(t1 - t0)
            door.append(t2 - t1 - (t1 - t0))
            one_by_one.append(t3 - t2)
    n_parts = len(standard.limits) + len(standard.tasks) + 1
    print(f"== the door a part goes through, puma_beam_limits ({len(states)} states, "
          f"{passes} passes; {n_parts} standard parts)")
    print(_line("the standard step's loop", np.array(base), len(base)))
    print(_line("one Python part (gives nothing)", np.array(door), len(door)))
    print(_line("the parts asked one by one", np.array(one_by_one), len(one_by_one)))
    print()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("configs", nargs="*",
                        default=["puma_beam_limits", "panda_pair", "both_sliding_bar"])
    parser.add_argument("--passes", type=int, default=3, help="replays of the states")
    parser.add_argument("--parts", action="store_true",
                        help="measure the door a part goes through instead")
    args = parser.parse_args(argv)
    if args.parts:
        parts(args.passes)
        return 0
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
