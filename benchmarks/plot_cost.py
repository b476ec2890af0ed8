"""What the plots cost: the same run with and without them, and ``collisions``, timed whole.

Each configuration is run from the command line, in a fresh process, once with
``--no-plots`` and once with the plots (``joints.png`` ... ``report.html``), alternately,
``--repeat`` times; the table gives the shortest wall time of each and their ratio (the
shortest, because other work on the machine only ever adds time). The processes' CPU time
(user + system, the children's, from ``resource``) is given beside it.

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
import subprocess
import sys
import tempfile
import time
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


def measure(variants: dict[str, list[str]], repeat: int, cache: Path,
            cold: bool) -> dict[str, tuple[float, float]]:
    """Time each variant ``repeat`` times, alternately; the shortest wall and CPU times."""
    best: dict[str, tuple[float, float]] = {}
    env = dict(os.environ)
    for k in range(repeat + 1):  # the first round fills the cache and is not counted
        for name, args in variants.items():
            env["DUALARM_QP_CACHE"] = str(cache / f"{name}{k}" if cold else cache)
            wall, cpu = timed(args, env)
            if k:
                old = best.get(name, (wall, cpu))
                best[name] = (min(old[0], wall), min(old[1], cpu))
    return best


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
              "   (wall, shortest of {}; CPU in brackets)".format(args.repeat))
        for name in names:
            path = Path(name) if name.endswith(".yaml") else ROOT / "configs" / f"{name}.yaml"
            out = str(tmp / path.stem)
            best = measure({"bare": ["run", str(path), "--out", out, "--force", "--quiet",
                                     "--no-plots"],
                            "plots": ["run", str(path), "--out", out, "--force", "--quiet"]},
                           args.repeat, cache, args.cold)
            (w0, c0), (w1, c1) = best["bare"], best["plots"]
            print(f"{path.stem:28s} {w0:6.2f} ({c0:5.2f}) {w1:6.2f} ({c1:5.2f}) {w1 / w0:6.2f}")
        for name in args.collisions:
            out = str(tmp / ("collisions_" + Path(name).stem))
            best = measure({"bare": ["collisions", name, "--out", out, "--quiet",
                                     "--no-plots"],
                            "plots": ["collisions", name, "--out", out, "--quiet"]},
                           args.repeat, cache, args.cold)
            (w0, c0), (w1, c1) = best["bare"], best["plots"]
            print(f"{'collisions ' + Path(name).stem:28s} {w0:6.2f} ({c0:5.2f}) "
                  f"{w1:6.2f} ({c1:5.2f}) {w1 / w0:6.2f}")


if __name__ == "__main__":
    main()
