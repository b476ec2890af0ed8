"""``dualarm-qp serve CONFIG --cell franka``: the file's two arms in franky-sim.

One MuJoCo scene (franky-sim) holds two FR3 arms at the file's bases (position and
yaw: franky-sim places a robot's base by position, and the cell turns it about the
vertical as the file's base does), each at the file's start joints, each served on its
own address with libfranka's network protocol (``cell.leader.address``,
``cell.follower.address``; loopback addresses such as 127.0.0.1 and 127.0.0.2). It
runs until interrupted (Ctrl-C, SIGTERM: exit code 130). The simulation steps 1 ms per
tick, at most ``pace`` seconds of the robots' time per second of wall time (``--pace``,
default :data:`PACE`; ``--realtime``: 1), and each tick waits for the command of every
moving arm, as a real robot's client on a real-time kernel answers every tick
(:func:`_tick`); the drive loop samples on the robots' own clock, so a slow simulation
only takes longer. Measured on two shared cores, a drive (Python, one step per 10 ms
sample) against the simulator at the wall clock's pace recorded the FR3 wrists' jerk
at up to 2 to 7 times the limit in 4 of 6 runs; at a quarter of it, 0.78 in each of 4.

The parser's part (:func:`add_serve_parser`) imports nothing heavy: NumPy, the
experiment and the simulator are imported by the functions that serve.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import numpy as np


def _yaw(T: np.ndarray) -> float:
    """Return the base's turn about the vertical [rad] (refusing a tilted base)."""
    from .base import CellSetupError

    R = T[:3, :3]
    if abs(R[2, 2] - 1.0) > 1e-9:
        raise CellSetupError("franky-sim places a robot upright: a base may only be turned "
                             "about the vertical")
    return math.atan2(R[1, 0], R[0, 0])


#: The simulator's default pace: seconds of the robots' time per second of wall time.
PACE = 0.25

#: Wall time [s] a tick waits for a moving arm's command before it steps without it.
COMMAND_WAIT = 0.25


#: The robot server's own (private) attributes :func:`_answered` reads: its motion mode
#: and whether a command came in this tick.
_MODE, _NEW = "_FrankaRobotServer__control_mode", "_FrankaRobotServer__has_new_command"


def _moving(rs: Any) -> bool:
    """Whether robot server ``rs`` runs a motion (its client answers every state)."""
    return bool(getattr(rs, _MODE).name != "IDLE")


def _answered(rs: Any) -> bool:
    """Whether robot server ``rs`` has its command for this tick (or needs none: idle)."""
    return not _moving(rs) or bool(getattr(rs, _NEW))


def _check_lockstep(server: Any) -> None:
    """Refuse a franky-sim whose robot servers do not say when a command came in."""
    from .base import CellSetupError

    for rs in server.robot_servers:
        if not (hasattr(rs, _MODE) and hasattr(rs, _NEW)):
            raise CellSetupError("this franky-sim does not say when a robot's command came "
                                 "in: serving needs franky-sim 1.0.4 (pip install "
                                 '"dualarm-qp[franka]")')


def _tick(server: Any, pace: float | None, moving: set[int]) -> int:
    """One 1 ms tick: every moving arm's command for the last state, a step, the states.

    A real Franka runs its 1 kHz loop against a client on a real-time kernel, which
    answers every state in time (a few missed answers in a row stop the robot on a
    reflex). The simulator instead steps as fast as the machine allows, and on a busy
    machine it would step past a command still on its way, repeating the last one: a
    motion delayed by a tick here and there, which a real robot does not show. So each
    tick waits for the command of every arm that was moving when the last state was
    sent (``moving``: the robot servers' indices, updated here), up to
    :data:`COMMAND_WAIT` of wall time: a client that stopped answering does not stop the
    simulation. An arm whose motion has just started has had no state to answer yet.
    Returns how many moving arms it stepped without their command.
    """
    start = time.monotonic()
    missed = 0
    for i, rs in enumerate(server.robot_servers):
        rs.process_commands()
        while i in moving and not _answered(rs) and time.monotonic() - start < COMMAND_WAIT:
            time.sleep(2e-5)
            rs.process_commands()
        missed += i in moving and not _answered(rs)
    server.sim.step()
    moving.clear()
    for i, rs in enumerate(server.robot_servers):
        rs.send_state()
        if _moving(rs):
            moving.add(i)
    if pace:
        time.sleep(max(0.0, 1e-3 / pace - (time.monotonic() - start)))
    return missed


def serve(config: Path, *, pace: float | None = PACE, ready: Any = None) -> tuple[str, int]:
    """Serve the file's two arms until interrupted (see the module).

    Parameters
    ----------
    config : Path
        The experiment file (its arms, bases, start and ``cell:`` addresses).
    pace : float or None
        At most this many seconds of the robots' time per second of wall time (None:
        as fast as the machine allows).
    ready : callable, optional
        Called with the addresses once both arms are served.

    Returns
    -------
    why : str
        What stopped it (``"SIGINT"``, ``"SIGTERM"``), once the arms are let go.
    missed : int
        How many times a moving arm was stepped without its command (its client did
        not answer within :data:`COMMAND_WAIT`).
    """
    import numpy as np

    from ..experiments.config import load_config
    from ..experiments.setup import build_experiment
    from .base import CellSetupError

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
        missed, moving = 0, set[int]()
        try:
            _check_lockstep(server)
            served = [rs.hostname for rs in server.robot_servers]
            for role, address, got in zip(("leader", "follower"), addresses, served,
                                          strict=True):
                if got != address:
                    raise CellSetupError(f"{config}: cell.{role}.address: {address} is "
                                         "taken: is another robot simulator serving there?")
            if ready is not None:
                ready(served)
            while True:
                missed += _tick(server, pace, moving)
        except KeyboardInterrupt as stop:
            why = str(stop) or "interrupt"
        finally:
            server.cleanup()
    return why, missed


def cmd_serve(args: argparse.Namespace) -> int:
    """``dualarm-qp serve``: exit 130 once interrupted and the served arms are let go."""
    from ..cli_commands import EXIT_INTERRUPTED
    from .base import CellSetupError

    if args.cell != "franka":
        raise CellSetupError(f"serve knows the cell 'franka' only, got {args.cell!r}")

    def ready(addresses: list[str]) -> None:
        print(f"serving {', '.join(addresses)} (libfranka's protocol, FR3); Ctrl-C stops",
              flush=True)

    if not args.pace > 0:
        raise CellSetupError(f"--pace must be > 0, got {args.pace:g}")
    why, missed = serve(args.config, pace=1.0 if args.realtime else args.pace, ready=ready)
    print(f"stopped ({why}): the served arms were let go"
          + (f"; {missed} ticks went without an arm's command" if missed else ""),
          file=sys.stderr)
    return EXIT_INTERRUPTED


def add_serve_parser(sub: Any) -> None:
    """Add ``serve`` to the command line's subcommands."""
    s = sub.add_parser("serve", help="serve the file's two arms in a simulator that speaks "
                       "the robots' protocol (Franka: franky-sim), until interrupted")
    s.add_argument("config", type=Path, help="experiment YAML file with a cell: section")
    s.add_argument("--cell", choices=("franka",), default="franka", help="the cell to serve")
    s.add_argument("--pace", type=float, default=PACE,
                   help=f"at most this many seconds of the robots' time per second of wall "
                        f"time (default {PACE:g})")
    s.add_argument("--realtime", action="store_true", help="no faster than the wall clock "
                   "(--pace 1)")
    s.set_defaults(func=cmd_serve)


__all__ = ["add_serve_parser", "cmd_serve", "serve"]
