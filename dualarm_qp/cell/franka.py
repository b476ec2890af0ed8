"""The Franka cell: two Franka arms through libfranka's network protocol (franky).

Each arm is a ``franky.Robot`` at its address (``cell.leader.address``,
``cell.follower.address``). A command is a joint-velocity motion, sent asynchronously:
the newer pre-empts the older, and franky's 1 kHz loop (in C++) goes from the current
rates to the new ones with its own trajectory generator (Ruckig), whose velocity,
acceleration and jerk limits are set to the arm's ``qd_max``, ``qdd_max`` and
``qddd_max`` (capped at the robot's own), so that what the robot executes between two
samples stays within them (``between = "interpolated"``). The motion holds its target
for ``hold`` seconds (the watchdog's age): a loop that stops sending leaves the arm
moving no longer than that.

The cell's clock is the robots' own (``RobotState.time``, from each robot's start,
millisecond resolution): the later of the two arms' clocks, each counted from when the
cell was opened; the reading's stamp is the older of the two. A robot that does not
answer when the cell opens is bad input; an error of franky or libfranka while the cell
runs (a reflex, a lost connection) stops it.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..experiments.config import ExperimentConfig
from ..experiments.setup import Experiment
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
        Per arm, ``(qd_max, qdd_max, qddd_max)`` [rad/s, rad/s^2, rad/s^3] for franky's
        trajectory generator (``inf``: the robot's own).
    hold : float
        How long a command is held after it is reached [s].
    """

    kind = "franka"
    between = "interpolated"

    def __init__(self, addresses: tuple[str, str],
                 limits: tuple[tuple[FloatArray, FloatArray, FloatArray], ...],
                 hold: float) -> None:
        self.addresses = addresses
        self.limits = limits
        self.hold_ms = max(1, round(hold * 1e3))
        self.robots: list[Any] = []
        self._t0 = [0.0, 0.0]

    def _connect(self, franky: Any, role: str, address: str) -> Any:
        try:
            return franky.Robot(address, realtime_config=franky.RealtimeConfig.Ignore)
        except Exception as err:  # franky's NetworkException and kin
            raise CellSetupError(f"cell.{role}.address: no Franka answers at {address} "
                                 f"({err}); is the robot (or 'dualarm-qp serve ... --cell "
                                 "franka') running there?") from None

    def open(self) -> Reading:
        """Connect to both arms, give franky the arms' limits, and read them."""
        franky = _franky()
        for role, address, (v, a, j) in zip(("leader", "follower"), self.addresses,
                                            self.limits, strict=True):
            robot = self._connect(franky, role, address)
            for limit, ours in ((robot.joint_velocity_limit, v),
                                (robot.joint_acceleration_limit, a),
                                (robot.joint_jerk_limit, j)):
                own = np.asarray(limit.max, dtype=np.float64)
                limit.set(np.minimum(own, np.where(np.isfinite(ours), ours, own)))
            self.robots.append(robot)
        self._t0 = [self._clock(r) for r in self.robots]
        return self.read()

    @staticmethod
    def _clock(robot: Any) -> float:
        return float(robot.state.time.to_sec())

    def read(self) -> Reading:
        """Return both arms' newest measured joints, stamped with the older clock."""
        try:
            states = [r.state for r in self.robots]
        except Exception as err:
            raise CellError(f"reading the Franka arms: {err}") from None
        t = min(float(s.time.to_sec()) - t0 for s, t0 in zip(states, self._t0, strict=True))
        return Reading(t, np.asarray(states[0].q, dtype=np.float64),
                       np.asarray(states[1].q, dtype=np.float64))

    def now(self) -> float:
        """Return the robots' clock [s] since the cell was opened (the later arm's)."""
        try:
            return max(self._clock(r) - t0 for r, t0 in zip(self.robots, self._t0, strict=True))
        except Exception as err:
            raise CellError(f"reading the Franka arms' clock: {err}") from None

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
        """Poll the robots' clock until it reaches ``t`` [s]."""
        last, since = self.now(), time.monotonic()
        while last < t - 1e-9:
            time.sleep(2e-4)
            now = self.now()
            if now > last:
                last, since = now, time.monotonic()
            elif time.monotonic() - since > CLOCK_TIMEOUT:
                raise CellError(f"the Franka arms' clock stood still for {CLOCK_TIMEOUT:g} s "
                                "of wall time: the robots stopped answering")

    def close(self) -> None:
        """Wait for the last motion to end, then let the robots go."""
        for robot in self.robots:
            try:
                robot.join_motion(timeout=1.0)
            except Exception as err:
                raise CellError(f"closing the Franka arms: {err}") from None
        self.robots = []


def franka_cell(cfg: ExperimentConfig, exp: Experiment, path: str) -> FrankaCell:
    """Build the Franka cell of the file's ``cell:`` section (not yet opened).

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
    from .settings import drive_settings

    hold = drive_settings(cfg, exp, dry_run=False).watchdog
    limits = tuple((arm.qd_max, arm.qdd_max, arm.qddd_max)
                   for arm in (exp.task.leader, exp.task.follower))
    return FrankaCell((addresses[0], addresses[1]), limits, hold)


__all__ = ["CLOCK_TIMEOUT", "FrankaCell", "franka_cell"]
