"""Time the Panda pair's step right after another step and after a pause, interleaved.

The 1 kHz loop (``examples/realtime_loop.py``) pauses between its ticks: it sleeps, then
spins the last 0.2 ms. This measures what a pause costs the step that follows it. The
states are those of the loop's task (``configs/panda_pair.yaml`` at 1 ms); each step is
timed after one of four pauses, the kind cycling step by step (so that every kind sees
the same machine state): none, a 0.2 ms spin, a 0.8 ms spin, a 0.8 ms sleep. Three
passes over the path's states; medians and p99 per kind.

Run it with ``python benchmarks/step_after_pause.py`` (about 20 s; needs the robots
extra).
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "examples"))

# The loop's task, sampled as the loop samples it (it imports dualarm_qp before NumPy).
import realtime_loop

# isort: split
import numpy as np

PASSES = 3


def _spin(seconds: float) -> None:
    until = time.perf_counter() + seconds
    while time.perf_counter() < until:
        pass


PAUSES: tuple[tuple[str, Callable[[], None]], ...] = (
    ("none", lambda: None),
    ("spin 0.2 ms", lambda: _spin(2e-4)),
    ("spin 0.8 ms", lambda: _spin(8e-4)),
    ("sleep 0.8 ms", lambda: time.sleep(8e-4)),
)


def main() -> int:
    """Print the step's median and p99 after each kind of pause."""
    exp = realtime_loop.experiment()
    controller = exp.controller()
    dt, end = exp.options.dt, exp.initial.t + exp.duration
    state, states = exp.initial, []
    while state.t < end - 1e-9:  # one pass of the path, as the loop runs it
        scale_max = min(1.0, (end - state.t) / dt)
        out = controller.step(state, scale_max=scale_max)
        states.append((state, scale_max))
        state = state.advanced(out, dt)
    times: dict[str, list[float]] = {name: [] for name, _ in PAUSES}
    for rep in range(PASSES):
        for i, (s, scale_max) in enumerate(states):
            name, pause = PAUSES[(i + rep) % len(PAUSES)]
            pause()
            t0 = time.perf_counter()
            controller.step(s, scale_max=scale_max)
            times[name].append(time.perf_counter() - t0)
    print(f"Panda pair at 1 ms, {len(states)} states, {PASSES} passes")
    for name, values in times.items():
        v = np.asarray(values) * 1e6
        print(f"  after {name:13s} median {np.median(v):6.0f} us   p99 "
              f"{np.percentile(v, 99):6.0f} us   ({v.size} steps)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
