"""``dualarm-qp serve CONFIG --cell franka``: the file's two arms in franky-sim.

One MuJoCo scene (franky-sim) holds two FR3 arms at the file's bases (position and
yaw: franky-sim places a robot's base by position, and the cell turns it about the
vertical as the file's base does), each at the file's start joints, each served on its
own address with libfranka's network protocol (``cell.leader.address``,
``cell.follower.address``; loopback addresses such as 127.0.0.1 and 127.0.0.2). It
runs until interrupted (Ctrl-C, SIGTERM: exit code 130). The simulation steps 1 ms per tick, as fast
as the machine allows (``--realtime``: no faster than the wall clock); the drive loop
samples on the robots' own clock, so a slow simulation only takes longer.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np

from ..experiments.config import load_config
from ..experiments.setup import build_experiment
from .base import CellSetupError


def _yaw(T: np.ndarray) -> float:
    """Return the base's turn about the vertical [rad] (refusing a tilted base)."""
    R = T[:3, :3]
    if abs(R[2, 2] - 1.0) > 1e-9:
        raise CellSetupError("franky-sim places a robot upright: a base may only be turned "
                             "about the vertical")
    return math.atan2(R[1, 0], R[0, 0])


def serve(config: Path, *, realtime: bool = False, ready: Any = None) -> str:
    """Serve the file's two arms until interrupted (see the module).

    Parameters
    ----------
    config : Path
        The experiment file (its arms, bases, start and ``cell:`` addresses).
    realtime : bool
        Step no faster than the wall clock.
    ready : callable, optional
        Called with the addresses once both arms are served.

    Returns
    -------
    str
        What stopped it (``"SIGINT"``, ``"SIGTERM"``), once the arms are let go.
    """
    try:
        import franky_sim
        from franky_sim.mujoco_simulator import MujocoSimulator
    except ImportError:
        raise CellSetupError('serving a Franka cell needs franky-sim: pip install '
                             '"dualarm-qp[franka]"') from None
    cfg = load_config(config)
    exp = build_experiment(cfg, str(config))
    addresses = []
    for role in ("leader", "follower"):
        address = getattr(cfg.cell, role).address
        if address is None:
            raise CellSetupError(f"{config}: cell.{role}.address: give each arm's address")
        addresses.append(address)
    with MujocoSimulator() as sim:
        for role, q0 in (("leader", exp.initial.q_l), ("follower", exp.initial.q_f)):
            arm = getattr(exp.task, role)
            if arm.n != 7:
                raise CellSetupError(f"{config}: {role}: franky-sim serves 7-joint FR3 arms")
            base = np.asarray(arm.base)
            sim.add_robot(initial_q=tuple(float(v) for v in q0),
                          position=tuple(float(v) for v in base[:3, 3]))
            yaw = _yaw(base)
            sim.worldbody[-1].set("quat", f"{math.cos(yaw / 2)} 0 0 {math.sin(yaw / 2)}")
        server = franky_sim.SimulationServer(sim, hostname_candidates=addresses)
        try:
            server.init()
        except OSError as err:
            server.cleanup()
            raise CellSetupError(f"{config}: cell: cannot serve the arms on "
                                 f"{', '.join(addresses)} ({err}): is another robot "
                                 "simulator serving there?") from None
        try:
            served = [rs.hostname for rs in server.robot_servers]
            for role, address, got in zip(("leader", "follower"), addresses, served,
                                          strict=True):
                if got != address:
                    raise CellSetupError(f"{config}: cell.{role}.address: {address} is "
                                         "taken: is another robot simulator serving there?")
            if ready is not None:
                ready(served)
            while True:
                server.run_once(realtime=realtime)
        except KeyboardInterrupt as stop:
            why = str(stop) or "interrupt"
        finally:
            server.cleanup()
    return why


def cmd_serve(args: argparse.Namespace) -> int:
    """``dualarm-qp serve``: exit 130 once interrupted and the served arms are let go."""
    from ..cli import EXIT_INTERRUPTED

    if args.cell != "franka":
        raise CellSetupError(f"serve knows the cell 'franka' only, got {args.cell!r}")

    def ready(addresses: list[str]) -> None:
        print(f"serving {', '.join(addresses)} (libfranka's protocol, FR3); Ctrl-C stops",
              flush=True)

    why = serve(args.config, realtime=args.realtime, ready=ready)
    print(f"stopped ({why}): the served arms were let go", file=sys.stderr)
    return EXIT_INTERRUPTED


def add_serve_parser(sub: Any) -> None:
    """Add ``serve`` to the command line's subcommands."""
    s = sub.add_parser("serve", help="serve the file's two arms in a simulator that speaks "
                       "the robots' protocol (Franka: franky-sim), until interrupted")
    s.add_argument("config", type=Path, help="experiment YAML file with a cell: section")
    s.add_argument("--cell", choices=("franka",), default="franka", help="the cell to serve")
    s.add_argument("--realtime", action="store_true", help="no faster than the wall clock")
    s.set_defaults(func=cmd_serve)


__all__ = ["add_serve_parser", "cmd_serve", "serve"]
