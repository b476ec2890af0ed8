"""The Franka cell: two Franka arms through libfranka's network protocol (franky).

Each arm is a ``franky.Robot`` at its address (``cell.leader.address``,
``cell.follower.address``). A command is a joint-velocity motion, sent asynchronously:
the newer pre-empts the older, and franky's 1 kHz loop (in C++) holds the new rates
from when it has reached them until the next command (``between = "held"``). franky
goes from the old rates to the new ones with its own trajectory generator, within the
robot's own velocity, acceleration and jerk limits (franky's defaults, left as they
are): it makes most of a change the clamp allows within a few milliseconds (the rest
within the sample), so the robot follows the commands as sent. The file's (tighter)
limits are kept by the commands themselves, sample by sample (the clamp,
:mod:`.safety`). Setting franky's limits to the file's
instead makes its generator reshape every change of rates into a jerk-limited ramp of
several samples: the arms then lag their commands by 30-40 ms and the grasp does not
hold.

A motion holds its target for ``hold`` seconds (the watchdog's age): a drive that
stops sending (killed, hung) leaves the arms moving no longer than that; franky then
brings them to rest within the robot's own limits.

The cell's clock is the robots' own (``RobotState.time``, millisecond resolution),
each arm's counted from when the cell was opened; :meth:`FrankaCell.now` is the later
of the two. :meth:`FrankaCell.wait_until` polls both arms' states until both have
reached the time asked and keeps each arm's first state at or after it, which
:meth:`FrankaCell.read` returns: a reading holds both arms at the sample's own tick of
their clocks (on hardware, two robots' ticks are up to 1 ms apart). When the poll came
late for an arm (its first state seen is a tick or more past the sample), its joints are
brought back to the sample's tick with its measured joint rates (the record's
``state_late`` says by how much): joints a millisecond off under the sample's stamp
would read, in the third differences of the record, as a jerk several times the limit.
The reading is stamped with the sample's tick (``robot_t``; the realised limits are
measured on those times), or, when an arm's state stopped coming, the earlier clock. A
robot that does not answer when the cell opens, or whose limits are below the file's,
is bad input; an error of franky or libfranka while the cell runs (a reflex, a lost
connection) stops it.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..experiments.config import ExperimentConfig
from ..experiments.experiment import Experiment
from .base import CellError, CellSetupError, Reading

FloatArray = NDArray[np.float64]

#: Wall time [s] the robots' clock may stand still before the cell gives up on them.
CLOCK_TIMEOUT = 5.0


def _franky() -> Any:
    try:
        import franky
    except ImportError:
        raise CellSetupError('the Franka cell needs franky: pip install "dualarm-qp[franka]"'
                             ) from None
    return franky


class FrankaCell:
    """Two Franka arms (see the module).

    Parameters
    ----------
    addresses : tuple of str
        The leader's and the follower's address.
    limits : tuple of tuple of ndarray
        Per arm, the file's ``(qd_max, qdd_max, qddd_max)`` [rad/s, rad/s^2, rad/s^3]:
        a robot whose own limits are below them is refused.
    hold : float
        How long a command is held after it is reached [s].
    """

    kind = "franka"
    between = "held"

    def __init__(self, addresses: tuple[str, str],
                 limits: tuple[tuple[FloatArray, FloatArray, FloatArray], ...],
                 hold: float) -> None:
        self.addresses = addresses
        self.limits = limits
        self.hold_ms = max(1, round(hold * 1e3))
        self.robots: list[Any] = []
        self._t0 = [0.0, 0.0]
        #: Each arm's state at the tick :meth:`wait_until` waited for (None: not kept).
        self._at: list[Any] = [None, None]
        #: The time the last :meth:`wait_until` asked for [s].
        self._asked = 0.0

    def _connect(self, franky: Any, role: str, address: str) -> Any:
        try:
            return franky.Robot(address, realtime_config=franky.RealtimeConfig.Ignore)
        except Exception as err:  # franky's NetworkException and kin
            raise CellSetupError(f"cell.{role}.address: no Franka answers at {address} "
                                 f"({err}); is the robot (or 'dualarm-qp serve ... --cell "
                                 "franka') running there?") from None

    @staticmethod
    def _check_limits(role: str, robot: Any, ours: tuple[FloatArray, ...]) -> None:
        """Refuse an arm whose own limits are below the file's."""
        for key, limit, value in zip(("qd_max", "qdd_max", "qddd_max"),
                                     (robot.joint_velocity_limit,
                                      robot.joint_acceleration_limit, robot.joint_jerk_limit),
                                     ours, strict=True):
            own = np.asarray(limit.max, dtype=np.float64)
            over = np.flatnonzero(np.asarray(value) > own * (1 + 1e-9))
            if over.size:
                j = int(over[0])
                raise CellSetupError(f"{role}.{key}: joint {j + 1}'s {float(value[j]):.6g} "
                                     f"(SI) is above the robot's own limit {own[j]:.6g}")

    def open(self) -> Reading:
        """Connect to both arms, check their limits against the file's, and read them."""
        franky = _franky()
        for role, address, ours in zip(("leader", "follower"), self.addresses, self.limits,
                                       strict=True):
            robot = self._connect(franky, role, address)
            self._check_limits(role, robot, ours)
            self.robots.append(robot)
        self._t0 = [self._clock(r) for r in self.robots]
        self._at = [None, None]
        return self.read()

    @staticmethod
    def _clock(robot: Any) -> float:
        return float(robot.state.time.to_sec())

    def _states(self) -> list[Any]:
        try:
            return [r.state for r in self.robots]
        except Exception as err:
            raise CellError(f"reading the Franka arms: {err}") from None

    def _since_open(self, states: list[Any]) -> list[float]:
        return [float(s.time.to_sec()) - t0 for s, t0 in zip(states, self._t0, strict=True)]

    def read(self) -> Reading:
        """Return both arms' joints at the sample's tick (see the module).

        After :meth:`wait_until`: each arm's state at the first tick it saw at or after
        the time asked (the sample's own tick, unless the poll came late), its joints
        brought back to the time asked with its measured rates (``Reading.late``: the
        latest arm's distance from it) and stamped with it; otherwise the newest states,
        stamped with the older arm's clock.
        """
        states = self._states()
        held = all(s is not None for s in self._at)
        states = [kept if kept is not None else s for kept, s in zip(self._at, states,
                                                                      strict=True)]
        self._at = [None, None]
        clocks = self._since_open(states)
        t = self._asked if held else min(clocks)
        q = [np.asarray(s.q, dtype=np.float64) - np.asarray(s.dq, dtype=np.float64) * (c - t)
             for s, c in zip(states, clocks, strict=True)]
        return Reading(t, q[0], q[1], late=max(clocks) - t)

    def now(self) -> float:
        """Return the robots' clock [s] since the cell was opened (the later arm's)."""
        return max(self._since_open(self._states()))

    def send(self, ql_dot: FloatArray, qf_dot: FloatArray) -> None:
        """Command both arms' joint velocities [rad/s] (asynchronous motions)."""
        franky = _franky()
        try:
            for robot, v in zip(self.robots, (ql_dot, qf_dot), strict=True):
                robot.move(franky.JointVelocityMotion(np.asarray(v, dtype=np.float64),
                                                      duration=franky.Duration(self.hold_ms)),
                           asynchronous=True)
        except Exception as err:
            raise CellError(f"commanding the Franka arms: {err}") from None

    def wait_until(self, t: float) -> None:
        """Poll the robots' states until both arms have reached ``t`` [s].

        Each arm's first state at or after ``t`` is kept for :meth:`read`. Returns early
        when one arm's clock is ``hold`` past ``t`` while the other's is not there yet
        (that arm's state stopped coming: the loop's watchdog judges it).

        Raises
        ------
        CellError
            Neither clock moved for :data:`CLOCK_TIMEOUT` seconds of wall time.
        """
        self._at = [None, None]
        self._asked = t
        last, since = -np.inf, time.monotonic()
        while True:
            states = self._states()
            clocks = self._since_open(states)
            for i, (state, clock) in enumerate(zip(states, clocks, strict=True)):
                if self._at[i] is None and clock >= t - 1e-9:
                    self._at[i] = state
            if all(s is not None for s in self._at) or max(clocks) >= t + self.hold_ms * 1e-3:
                return
            if max(clocks) > last:
                last, since = max(clocks), time.monotonic()
            elif time.monotonic() - since > CLOCK_TIMEOUT:
                raise CellError(f"the Franka arms' clock stood still for {CLOCK_TIMEOUT:g} s "
                                "of wall time: the robots stopped answering")
            time.sleep(5e-5)

    def close(self) -> None:
        """Wait for the last motion to end, then let the robots go."""
        robots, self.robots = self.robots, []
        for robot in robots:
            try:
                robot.join_motion(timeout=1.0)
            except Exception as err:
                raise CellError(f"closing the Franka arms: {err}") from None


def franka_cell(cfg: ExperimentConfig, exp: Experiment, path: str, hold: float
                ) -> FrankaCell:
    """Build the Franka cell of the file's ``cell:`` section (not yet opened).

    ``hold`` [s] is how long a command is held after it is reached (the watchdog's age).

    Raises
    ------
    CellSetupError
        An arm without an address, or one that is not a 7-joint arm.
    """
    addresses = []
    for role in ("leader", "follower"):
        address = getattr(cfg.cell, role).address
        if address is None:
            raise CellSetupError(f"{path}: cell.{role}.address: the Franka cell needs each "
                                 "arm's address (e.g. 127.0.0.1)")
        if getattr(exp.task, role).n != 7:
            raise CellSetupError(f"{path}: {role}: a Franka arm has 7 joints, the file's has "
                                 f"{getattr(exp.task, role).n}")
        addresses.append(address)
    limits = tuple((arm.qd_max, arm.qdd_max, arm.qddd_max)
                   for arm in (exp.task.leader, exp.task.follower))
    return FrankaCell((addresses[0], addresses[1]), limits, hold)


__all__ = ["CLOCK_TIMEOUT", "FrankaCell", "franka_cell"]
