"""What the plots cost: the same run with and without them, and ``collisions``, timed whole.

Each configuration is run from the command line, in a fresh process, once with
``--no-plots`` and once with the plots (``joints.png`` ... ``report.html``), alternately,
``--repeat`` times. The table gives the median wall time of each, the median of the
rounds' ratios (each round's two runs side by side, so that a burst of other work on
the machine falls on both alike) and the shortest wall time of each. The processes' CPU
time (user + system, the command's and its children's, from ``resource``; median) is
given beside it. Wall time is the whole command's, until it exits: every output file,
the figures included, is written by then.

``--collisions FILE`` times ``dualarm-qp collisions FILE`` (three runs, their plots and
the comparison figure) the same way.

Fitted capsules are kept on disk between processes (``DUALARM_QP_CACHE``, see
docs/collisions.md). By default each timed process finds them there (a warm cache: the
case of every run after the first); ``--cold`` gives every process an empty cache folder
of its own, so that each one fits its capsules again.

Run it with ``python benchmarks/plot_cost.py [config ...] [--collisions FILE ...]
[--repeat 3] [--cold]``. It is a benchmark, not a test: it asserts nothing about speed.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CONFIGS = ("ur5_pair_sliding_bar", "panda_pair", "baxter_tray", "puma_beam_limits",
           "ur5_pair_collision", "panda_pair_shelf")


def timed(args: list[str], env: dict[str, str]) -> tuple[float, float]:
    """Run ``python -m dualarm_qp ARGS``; return its wall and CPU time [s]."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "dualarm_qp", *args], env=env,
                          stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                          check=False)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode not in (0, 1):
        raise SystemExit(f"{' '.join(args)} exited with {done.returncode}:\n{done.stderr}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu


@dataclass(frozen=True)
class Timing:
    """What :func:`measure` found for one command: ``repeat`` wall and CPU times [s]."""

    wall: list[float]
    cpu: list[float]

    @property
    def median(self) -> float:
        """Median wall time [s]."""
        return statistics.median(self.wall)


def measure(variants: dict[str, list[str]], repeat: int, cache: Path,
            cold: bool) -> dict[str, Timing]:
    """Time each variant ``repeat`` times, alternately; every round's wall and CPU times."""
    found: dict[str, Timing] = {name: Timing([], []) for name in variants}
    env = dict(os.environ)
    for k in range(repeat + 1):  # the first round fills the cache and is not counted
        for name, args in variants.items():
            env["DUALARM_QP_CACHE"] = str(cache / f"{name}{k}" if cold else cache)
            wall, cpu = timed(args, env)
            if k:
                found[name].wall.append(wall)
                found[name].cpu.append(cpu)
    return found


def row(label: str, found: dict[str, Timing]) -> str:
    """One line of the table: median wall (CPU) of each, median ratio, shortest walls."""
    bare, plots = found["bare"], found["plots"]
    ratio = statistics.median(p / b for p, b in zip(plots.wall, bare.wall, strict=True))
    return (f"{label:28s} {bare.median:6.2f} ({statistics.median(bare.cpu):5.2f}) "
            f"{plots.median:6.2f} ({statistics.median(plots.cpu):5.2f}) {ratio:6.2f}"
            f"   {min(bare.wall):5.2f} {min(plots.wall):5.2f}")


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("configs", nargs="*", help=f"configs/<name>.yaml names or paths "
                                                   f"(default: {', '.join(CONFIGS)})")
    parser.add_argument("--collisions", nargs="*", default=[], metavar="FILE",
                        help="also time 'dualarm-qp collisions FILE'")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--cold", action="store_true",
                        help="an empty capsule cache for every process")
    args = parser.parse_args(argv)
    names = args.configs or ([] if args.collisions else list(CONFIGS))
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        cache = tmp / "cache"
        print(f"{'config':28s} {'no plots [s]':>14s} {'plots [s]':>14s} {'ratio':>6s}"
              f"   {'shortest':>11s}   (wall, median of {args.repeat}; CPU in brackets)")
        for name in names:
            path = Path(name) if name.endswith(".yaml") else ROOT / "configs" / f"{name}.yaml"
            out = str(tmp / path.stem)
            found = measure({"bare": ["run", str(path), "--out", out, "--force", "--quiet",
                                      "--no-plots"],
                             "plots": ["run", str(path), "--out", out, "--force", "--quiet"]},
                            args.repeat, cache, args.cold)
            print(row(path.stem, found), flush=True)
        for name in args.collisions:
            out = str(tmp / ("collisions_" + Path(name).stem))
            found = measure({"bare": ["collisions", name, "--out", out, "--quiet",
                                      "--no-plots"],
                             "plots": ["collisions", name, "--out", out, "--quiet"]},
                            args.repeat, cache, args.cold)
            print(row("collisions " + Path(name).stem, found), flush=True)

if __name__ == "__main__":
    main()
