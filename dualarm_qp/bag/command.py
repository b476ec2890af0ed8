"""``dualarm-qp bag RUN_DIR``: a finished run (simulated or driven) as a rosbag2 in MCAP."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from .messages import TOPICS


def cmd_bag(args: argparse.Namespace) -> int:
    """``dualarm-qp bag``: write the bag; exit 0, or 2 on bad input."""
    from .write import write_bag

    path, counts = write_bag(args.run_dir, args.out, force=args.force)
    shown = ", ".join(f"{topic} {counts[topic]}" for topic in TOPICS)
    print(f"bag: {path} (rosbag2, MCAP; messages: {shown})")
    return 0


def add_bag_parser(sub: Any) -> None:
    """Add ``bag`` to the command line's subcommands."""
    b = sub.add_parser("bag", help="write a finished run (run or drive) as a rosbag2 in MCAP: "
                       "joint states with the grasp, the object and D(t) on /tf, the status")
    b.add_argument("run_dir", type=Path, metavar="RUN_DIR", help="the run's output folder")
    b.add_argument("--out", type=Path, help="the bag's folder (default RUN_DIR/bag)")
    b.add_argument("--force", action="store_true", help="replace an existing bag there")
    b.set_defaults(func=cmd_bag)


__all__ = ["add_bag_parser", "cmd_bag"]
