"""Step a simulated Panda pair at 1 kHz and count the deadline misses.

A real-time loop on a fixed 1 ms grid: at each tick the controller steps for the
measured state, and its command must be ready before the next tick (the deadline).
The "robot" is simulated: the rates are integrated for one 1 ms sample (explicit
Euler), so path time advances with the ticks. The task is configs/panda_pair.yaml
(two 7-joint Pandas carrying a bar, a sliding grasp, speed-capped joints, the exact
nullspace solver with the scale policy) sampled at 1 ms instead of the file's 10 ms.

The path lasts 3 s. When it ends the pair starts it again from its initial state, at
rest (the controller's warm start is forgotten), so a 60 s run is about 20 passes and
holds every kind of step the task has: the start, full-speed steps, and the steps the
scale policy slows (all joints reach their speed limits on this path).

Timing (``time.perf_counter``): tick k is due at ``t0 + k ms``. The loop waits for it
on the core it runs on (``--wait spin``, the default: it checks the clock until the tick
is due, as a real-time loop on a core of its own does), or sleeps until shortly before
the tick and spins the rest (``--wait sleep``: the core is free between steps, but the
operating system wakes the loop late now and then, and a step that follows a sleep runs
slower: ``benchmarks/step_after_pause.py``). A step must finish by the next tick, its
deadline. A step that finishes later is a miss, and so is every tick it overran: no new
step starts for those (the arms keep the late command through them, and the plant
integrates it); the next step starts at the next tick. The miss rate is the share of the
ticks that got no new command on time.

Run it with ``python examples/realtime_loop.py`` (60 s; ``--seconds 5`` for a short
run). Needs the robots extra: ``pip install "dualarm-qp[robots]"``. The loop runs on
one core (all of it with ``--wait spin``); other work on the machine shows as misses.

``--realtime`` (Linux) runs the loop as a real-time control process is run: pinned to
one core (the last it may use), with its memory locked in RAM (no page faults in a
step) and at a real-time priority (``SCHED_FIFO`` 40), so that ordinary processes wait
when its tick comes (interrupt threads, at 50, still come first). It needs the rights
to do so: root, or the ``CAP_SYS_NICE`` and ``CAP_IPC_LOCK`` capabilities, or limits
that allow both (an ``rtprio`` limit of at least 40, and a locked-memory limit,
``ulimit -l``, above the process's size, a few hundred MB). Without them the example
says which step was refused and stops. It waits by sleeping: a loop spinning at a
real-time priority would keep its core from everything else, and Linux stops real-time
processes for the rest of each second once they have had
``kernel.sched_rt_runtime_us`` of it (950,000 us by default).
"""

from __future__ import annotations

import argparse
import ctypes
import math
import os
import sys
import time
from dataclasses import dataclass
from pathlib import Path

# dualarm_qp first: it asks NumPy's BLAS for one thread, which only works before NumPy
# is loaded. A threaded BLAS hands each tiny matrix of a step to its threads and makes
# a step ten times slower on a busy machine.
import dualarm_qp as dq

# isort: split
import numpy as np

CONFIG = Path(__file__).resolve().parents[1] / "configs" / "panda_pair.yaml"
PERIOD = 1e-3  # tick [s]: 1 kHz
PARTS = ("kinematics", "assembly", "solve", "verify")
#: How the loop waits for a tick: check the clock until it is due, or sleep first.
WAITS = ("spin", "sleep")
#: The real-time priority of ``--realtime`` (SCHED_FIFO, 1 to 99; below the kernel's own
#: interrupt threads, at 50).
PRIORITY = 40
#: mlockall's flags: the pages mapped now and those mapped later (Linux).
MCL_CURRENT, MCL_FUTURE = 1, 2


@dataclass
class LoopReport:
    """What a run of the loop measured.

    Attributes
    ----------
    seconds : float
        Wall time asked for [s].
    wall : float
        Wall time the loop took [s].
    ticks : int
        1 ms ticks in ``seconds``.
    passes : int
        Times the path was completed (then restarted from its start).
    stopped : int
        Steps with no usable command (the arms stop; the path is restarted).
    ran : ndarray of bool, shape (ticks,)
        Per tick: a step started at it (False: a late step was still running, the tick
        was skipped).
    step_time : ndarray, shape (steps,)
        Wall time of each ``controller.step`` call [s].
    cpu_time : ndarray, shape (steps,)
        CPU time of the loop's thread during each step [s] (below ``step_time``: the
        process was not running for the difference, other work had the core).
    late_start : ndarray, shape (steps,)
        How long after its tick each step started [s] (the loop wakes a little late).
    finish : ndarray, shape (steps,)
        When each step finished, after its tick [s]; above ``PERIOD`` is a miss.
    split : ndarray, shape (steps, 4)
        The step's own split of its time (``out.times``): kinematics, assembly, solve,
        verify [s].
    slowed : ndarray of bool, shape (steps,)
        The scale policy slowed the path on this step (a search over the task scale).
    rates : ndarray, shape (ticks, n)
        The rates the plant integrated over each tick [rad/s, m/s], in the controller's
        decision order (``names``).
    names : tuple of str
        The decision variables.
    wait : str
        How the loop waited for each tick (:data:`WAITS`).
    steal : ndarray or None, shape (cores,)
        Per core, the time the host gave to other virtual machines while this one
        wanted to run, during the loop [s] (Linux's steal time, counted in 10 ms
        units); None where the system does not say.
    """

    seconds: float
    wall: float
    ticks: int
    passes: int
    stopped: int
    ran: np.ndarray
    step_time: np.ndarray
    cpu_time: np.ndarray
    late_start: np.ndarray
    finish: np.ndarray
    split: np.ndarray
    slowed: np.ndarray
    rates: np.ndarray
    names: tuple[str, ...]
    wait: str = "spin"
    steal: np.ndarray | None = None

    @property
    def steps(self) -> int:
        """Controller steps run (one per tick that was not skipped)."""
        return int(self.ran.sum())

    @property
    def late(self) -> np.ndarray:
        """Per step: it finished after its tick's deadline."""
        return self.finish > PERIOD

    @property
    def misses(self) -> int:
        """Ticks with no new command by their deadline: late steps and skipped ticks."""
        return int(self.late.sum()) + self.ticks - self.steps

    @property
    def longest_miss_run(self) -> int:
        """Most consecutive ticks that missed."""
        missed = ~self.ran
        missed[np.flatnonzero(self.ran)[self.late]] = True
        best = run = 0
        for m in missed:
            run = run + 1 if m else 0
            best = max(best, run)
        return best


def experiment(config: Path = CONFIG) -> dq.Experiment:
    """Return the experiment of ``config`` sampled at the loop's 1 ms."""
    return dq.build_experiment(dq.load_config(config), str(config), dt=PERIOD)


def steal_times() -> np.ndarray | None:
    """Each core's steal time so far [s] (``/proc/stat``), or None where there is none."""
    try:
        lines = Path("/proc/stat").read_text().splitlines()
        ticks = [int(line.split()[8]) for line in lines
                 if line.startswith("cpu") and line[3:4].isdigit()]
        hz = os.sysconf("SC_CLK_TCK")
    except (OSError, ValueError, IndexError, AttributeError):
        return None
    return np.array(ticks, dtype=float) / hz if ticks else None


def wait_until(t: float, wait: str = "spin") -> None:
    """Wait until ``t`` (perf_counter time [s]): check the clock, or sleep first.

    ``"sleep"`` sleeps until shortly before ``t`` (a sleep wakes up about 0.1 ms late,
    more on a busy machine), then checks the clock for the rest.
    """
    if wait == "sleep":
        ahead = t - time.perf_counter() - 2e-4
        if ahead > 0:
            time.sleep(ahead)
    while time.perf_counter() < t:
        pass


def go_realtime(priority: int = PRIORITY) -> str:
    """Put this process on one core, lock its memory and give it a real-time priority.

    Returns one line saying what was set. Raises OSError (``PermissionError`` without
    the right to do it) naming the step that was refused; nothing before it is undone
    (the process ends).
    """
    if not hasattr(os, "sched_setscheduler"):
        raise OSError("real-time scheduling needs Linux (os.sched_setscheduler)")
    core = max(os.sched_getaffinity(0))
    try:
        os.sched_setaffinity(0, {core})
    except OSError as err:
        raise OSError(err.errno, f"the core (sched_setaffinity {core}): {err.strerror}"
                      ) from None
    libc = ctypes.CDLL(None, use_errno=True)
    if libc.mlockall(MCL_CURRENT | MCL_FUTURE) != 0:
        err = ctypes.get_errno()
        raise OSError(err, f"locking the memory (mlockall): {os.strerror(err)} (it needs "
                           "CAP_IPC_LOCK, or a locked-memory limit, ulimit -l, above the "
                           "process's size)")
    try:
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(priority))
    except OSError as err:
        raise OSError(err.errno, f"the real-time priority (SCHED_FIFO {priority}): "
                                 f"{err.strerror} (it needs CAP_SYS_NICE, or an rtprio limit "
                                 f"of at least {priority})") from None
    return f"real time: pinned to core {core}, memory locked, SCHED_FIFO priority {priority}"


def run(seconds: float, config: Path = CONFIG, wait: str = "spin",
        exp: dq.Experiment | None = None) -> LoopReport:
    """Run the 1 kHz loop for ``seconds`` of ticks and return what it measured.

    ``wait`` is how the loop waits for each tick (:data:`WAITS`, :func:`wait_until`);
    ``exp`` the experiment of ``config`` made already (:func:`experiment`).
    """
    if wait not in WAITS:
        raise ValueError(f"wait must be one of {', '.join(WAITS)}, got {wait!r}")
    exp = experiment(config) if exp is None else exp
    controller = exp.controller()
    dt, path_end = exp.options.dt, exp.initial.t + exp.duration
    ticks = max(1, round(seconds / PERIOD))
    n = len(controller.names)
    # Everything recorded goes into arrays allocated before the loop starts.
    step_time, late_start, finish = np.zeros(ticks), np.zeros(ticks), np.zeros(ticks)
    cpu_time = np.zeros(ticks)
    split, slowed, rates = np.zeros((ticks, 4)), np.zeros(ticks, bool), np.zeros((ticks, n))
    ran = np.zeros(ticks, bool)
    passes = stopped = 0
    state = exp.initial
    controller.step(state)  # one step before the clock starts (first-call set-ups)
    controller.reset()
    steal_before = steal_times()
    t0 = time.perf_counter() + PERIOD
    k = 0
    while k < ticks:
        due = t0 + k * PERIOD
        wait_until(due, wait)
        start, cpu = time.perf_counter(), time.thread_time()
        scale_max = min(1.0, (path_end - state.t) / dt)  # never ask past the path's end
        out = controller.step(state, scale_max=scale_max)
        end, cpu_time[k] = time.perf_counter(), time.thread_time() - cpu
        # The command is ready: the rest of the tick is the simulated plant's.
        step_time[k], late_start[k], finish[k] = end - start, start - due, end - due
        tm = out.times
        split[k] = (tm.kinematics, tm.assembly, tm.solve, tm.verify)
        slowed[k] = out.scale < scale_max
        ran[k] = True
        if not out.applied:  # no usable command: the arms stop; start the path again
            stopped += 1
            state = exp.initial
            controller.reset()
            k += 1
            while k < ticks and t0 + k * PERIOD < end:  # overran: the arms stand still
                k += 1
            continue
        x = controller.layout.join(out.ql_dot, out.qf_dot, out.m, out.m_leader)
        # The ticks whose period began before this step finished get no step of their
        # own: the arms keep the command through them (one tick when it was on time).
        while True:
            rates[k] = x
            state = state.advanced(out, dt)
            k += 1
            if state.t >= path_end - 1e-9:  # the path is done: start it again, at rest
                passes += 1
                state = exp.initial
                controller.reset()
                break
            if k >= ticks or t0 + k * PERIOD >= end:
                break
    wall = time.perf_counter() - t0
    steal_after = steal_times()
    steal = (steal_after - steal_before if steal_before is not None and steal_after is not None
             and steal_after.shape == steal_before.shape else None)
    return LoopReport(seconds, wall, ticks, passes, stopped, ran, step_time[ran],
                      cpu_time[ran], late_start[ran], finish[ran], split[ran], slowed[ran], rates,
                      tuple(controller.names), wait, steal)


def why(report: LoopReport) -> str:
    """Return one line: where the time of the late steps went, against those on time."""
    late = report.late
    if not late.any():
        return "why: no step was late"

    def us(values: np.ndarray, sel: np.ndarray) -> float:
        return float(values[sel].mean() * 1e6)

    wall, cpu = us(report.step_time, late), us(report.cpu_time, late)
    parts = ", ".join(f"{p} {us(report.split[:, i], late):.0f}"
                      for i, p in enumerate(PARTS))
    line = (f"why: a late step took {wall:.0f} us on average, {cpu:.0f} us of it on the "
            f"CPU ({max(wall - cpu, 0.0):.0f} us the process waited while other work had "
            f"the core); "
            f"its split: {parts} us; it started {us(report.late_start, late):.0f} us after "
            f"its tick")
    if (~late).any():
        line += (f"; a step on time took {us(report.step_time, ~late):.0f} us "
                 f"(solve {us(report.split[:, 2], ~late):.0f} us)")
    line += f"; {report.slowed[late].mean():.0%} of the late steps were slowed by the scale policy"
    return line


def summary(report: LoopReport) -> str:
    """Return the report as text, one measure per line."""
    us = report.step_time * 1e6
    late = int(report.late.sum())
    lines = [
        f"Panda pair at 1 kHz for {report.wall:.3f} s of wall time, waiting by "
        f"{report.wait} (passes of the path: {report.passes}, stops: {report.stopped})",
        f"ticks: {report.ticks} ({report.steps} steps, {report.ticks - report.steps} "
        f"skipped while a late step ran)",
        f"misses: {report.misses} ({late} late steps + {report.ticks - report.steps} "
        f"skipped ticks)",
        f"miss rate: {report.misses / report.ticks:.3%}",
        f"longest run of misses: {report.longest_miss_run} ticks",
        f"step time: median {np.median(us):.0f} us, p99 {np.percentile(us, 99):.0f} us, "
        f"max {us.max():.0f} us",
        f"slowed steps (scale policy): {int(report.slowed.sum())} of {report.steps}",
        why(report),
    ]
    if report.steal is not None:
        per_core = ", ".join(f"{1e3 * v:.0f}" for v in report.steal)
        lines.append(f"steal: the host gave {1e3 * report.steal.sum():.0f} ms of this "
                     f"machine's cores to other virtual machines during the loop (per core: "
                     f"{per_core} ms; counted in 10 ms units)")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    """Command line: ``--seconds`` of ticks (default 60), ``--wait spin|sleep``, ``--realtime``."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=60.0,
                        help="wall time to run at 1 kHz [s] (default 60)")
    parser.add_argument("--wait", choices=WAITS, default=None,
                        help="check the clock until each tick (spin, the default: the "
                             "loop keeps its core) or sleep until shortly before it "
                             "(the default with --realtime)")
    parser.add_argument("--realtime", action="store_true",
                        help="run on one core with locked memory at a real-time priority "
                             "(Linux; needs root or CAP_SYS_NICE and CAP_IPC_LOCK)")
    args = parser.parse_args(argv)
    if not (math.isfinite(args.seconds) and args.seconds > 0):
        parser.error("--seconds must be a positive number")
    wait = args.wait or ("sleep" if args.realtime else "spin")
    if args.realtime and wait == "spin":
        parser.error("--realtime waits by sleep: a loop spinning at a real-time priority "
                     "keeps its core from everything else, and Linux stops it for the rest "
                     "of each second once it has had kernel.sched_rt_runtime_us of it")
    try:
        exp = experiment()  # before the real-time set-up: the model loads normally
    except dq.RobotModelError as err:  # the Panda comes from example-robot-data
        print(f"{err}\nInstall it with: pip install 'dualarm-qp[robots]'", file=sys.stderr)
        return 1
    if args.realtime:
        try:
            print(go_realtime())
        except OSError as err:
            print(f"--realtime: refused: {err.strerror or err}", file=sys.stderr)
            return 1
    print(summary(run(args.seconds, wait=wait, exp=exp)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
