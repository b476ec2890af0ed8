"""A cell: two arms that are read and commanded, whatever drives them.

:class:`Cell` is the one interface the drive loop (:mod:`.loop`) talks to. A back-end
(MuJoCo, ROS 2, Franka) implements five methods:

* ``open()``: connect, and return the first :class:`Reading`;
* ``read()``: the newest measured joints of both arms, stamped with the cell's clock;
* ``send(ql_dot, qf_dot)``: both arms' joint rates [rad/s], applied until the next send
  (how the driver goes from one to the next is the back-end's: :attr:`Cell.between`);
* ``wait_until(t)``: return once the cell's clock has reached ``t`` [s];
* ``close()``: disconnect (after the loop has brought the arms to rest).

``now()`` is the cell's clock [s]: the simulation time of a simulator, the ROS clock of
a ROS 2 graph, the robot's own clock of a Franka. The loop samples on that clock, never
on the wall clock, so a simulator slower than real time is driven at its own pace.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from ..errors import DualArmError, InvalidInputError

FloatArray = NDArray[np.float64]


class CellError(DualArmError):
    """A cell stopped answering, or cannot be opened.

    A robot that does not answer, a lost connection, a driver error. A run it stops
    fails (exit code 1); one it refuses to open is bad input (exit code 2).
    """


class CellSetupError(InvalidInputError):
    """A cell cannot be set up from the file (an unknown joint name, a missing address)."""


@dataclass(frozen=True)
class Reading:
    """Both arms' measured joints at one instant of the cell's clock.

    Attributes
    ----------
    t : float
        The cell's clock when the joints were measured [s] (the newer of the two arms'
        stamps when they come separately).
    q_l, q_f : ndarray
        Leader and follower joints [rad], in the arms' own order.
    sigma : float
        The grasp coordinate a simulator measured [m] (NaN on hardware: no encoder).
    late : float
        How far past ``t`` the later arm's state was stamped [s] (0: both at ``t``);
        the back-end brought its joints back to ``t``.
    """

    t: float
    q_l: FloatArray
    q_f: FloatArray
    sigma: float = float("nan")
    late: float = 0.0


class Cell(Protocol):
    """Two arms the drive loop reads and commands (see the module)."""

    #: ``"held"`` or ``"interpolated"``: what the driver does between two sends.
    between: str
    #: The back-end's name (``"mujoco"``, ``"ros2"``, ``"franka"``).
    kind: str

    def open(self) -> Reading:
        """Connect and return the first reading."""

    def read(self) -> Reading:
        """Return the newest reading (it may be older than :meth:`now`)."""

    def now(self) -> float:
        """Return the cell's clock [s]."""

    def send(self, ql_dot: FloatArray, qf_dot: FloatArray) -> None:
        """Command both arms' joint rates [rad/s]."""

    def wait_until(self, t: float) -> None:
        """Return once :meth:`now` has reached ``t`` [s]."""

    def close(self) -> None:
        """Disconnect."""


def zeros_like(reading: Reading) -> tuple[FloatArray, FloatArray]:
    """Zero rates for both arms of ``reading``."""
    return np.zeros_like(reading.q_l), np.zeros_like(reading.q_f)


__all__ = ["Cell", "CellError", "CellSetupError", "Reading", "zeros_like"]
