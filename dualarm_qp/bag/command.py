"""``dualarm-qp bag RUN_DIR``: a finished run (simulated or driven) as a rosbag2 in MCAP.

With ``--foxglove``, the same stream is served live instead (:mod:`.live`), replayed at
the pace of the run's clock until interrupted (Ctrl-C or SIGTERM: exit 130).
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from .topics import DEFAULT_PORT, TOPICS


def serve_run(args: argparse.Namespace) -> int:
    """Replay the run in a live view until interrupted."""
    from .live import LiveView, replay
    from .write import RunStream

    stream = RunStream.read(args.run_dir)
    messages = list(stream.stream())
    view = LiveView(stream.messages.store, port=args.port)
    try:
        print(f"serving {args.run_dir} at {view.url} (Foxglove WebSocket; the run replayed "
              f"at {args.rate:g}x, {len(messages)} messages a pass); Ctrl-C stops", flush=True)
        replay(view, messages, rate=args.rate)
    finally:
        view.close()
    return 0


def cmd_bag(args: argparse.Namespace) -> int:
    """``dualarm-qp bag``: write the bag (or serve it); exit 0, or 2 on bad input."""
    from .write import write_bag

    if args.foxglove:
        return serve_run(args)
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
    b.add_argument("--foxglove", action="store_true",
                   help="serve the same stream live on 127.0.0.1 instead (Foxglove WebSocket), "
                   "replayed until interrupted")
    b.add_argument("--port", type=int, default=DEFAULT_PORT,
                   help=f"the live view's port (default {DEFAULT_PORT}; 0: any free one)")
    b.add_argument("--rate", type=float, default=1.0,
                   help="the replay's speed: run time per wall time (default 1)")
    b.set_defaults(func=cmd_bag)


__all__ = ["add_bag_parser", "cmd_bag"]
