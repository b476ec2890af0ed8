"""The MuJoCo cell: the task's MuJoCo plant (``docs/physics.md``) behind the cell interface.

The arms are the plant's joint servos at 1 ms substeps; the cell's clock is the
simulation's time, which advances only while :meth:`MujocoCell.wait_until` steps it, one
controller sample at a time, so the loop runs as fast as the machine allows (or, with
``realtime``, no faster than the wall clock). Between two sends the servos' rate
reference is ramped from the previous command to the new one over the sample
(``between = "interpolated"``). The simulated grasp coordinate is handed on as
:attr:`Reading.sigma <.base.Reading.sigma>` (recorded as ``grasp_measured``); the loop
still estimates the grasp from the joints, as on hardware.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..physics.plant import MujocoPlant
from ..step.state import DualArmState
from .base import Reading

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class _Rates:
    """The rates sent, as the plant's command (the grasp slides passively)."""

    ql_dot: FloatArray
    qf_dot: FloatArray
    m: float = 0.0
    m_leader: float = 0.0
    scale: float = 0.0


class MujocoCell:
    """Two simulated arms (see the module).

    Parameters
    ----------
    plant : MujocoPlant
        The task's plant (:class:`~dualarm_qp.physics.plant.MujocoPlant`).
    start : DualArmState
        Where the simulated arms start (the file's start).
    dt : float
        The controller's sampling interval [s]: the simulation advances in steps of it.
    realtime : bool
        Pace the simulation to the wall clock.
    """

    kind = "mujoco"
    between = "interpolated"

    def __init__(self, plant: MujocoPlant, start: DualArmState, dt: float, *,
                 realtime: bool = False) -> None:
        self.plant = plant
        self.start = start
        self.dt = float(dt)
        self.realtime = realtime
        self._t = 0.0
        self._wall0 = 0.0
        self._rates = _Rates(np.zeros_like(start.q_l), np.zeros_like(start.q_f))
        self._state = start

    def open(self) -> Reading:
        """Build the simulation at the start (settled under the load) and read it."""
        self.plant.reset(self.start, self.dt)
        self._state = self.plant._measure(self.start.t)  # the settled start, as measured
        self._t = 0.0
        self._wall0 = time.perf_counter()
        return self.read()

    def read(self) -> Reading:
        """Return the state at the end of the last simulated sample."""
        s = self._state
        return Reading(self._t, s.q_l.copy(), s.q_f.copy(), float(s.sigma))

    def now(self) -> float:
        """Return the simulation's time [s]."""
        return self._t

    def send(self, ql_dot: FloatArray, qf_dot: FloatArray) -> None:
        """Set the rates the servos follow from the next sample on [rad/s]."""
        self._rates = _Rates(np.asarray(ql_dot, dtype=np.float64).copy(),
                             np.asarray(qf_dot, dtype=np.float64).copy())

    def wait_until(self, t: float) -> None:
        """Simulate whole samples until the simulation's time reaches ``t`` [s]."""
        while self._t < t - 1e-9 * max(1.0, abs(t)):
            self._state = self.plant.advance(self._state, self._rates, self.dt)
            self._t += self.dt
            if self.realtime:
                time.sleep(max(0.0, self._wall0 + self._t - time.perf_counter()))

    def close(self) -> None:
        """Nothing to release."""


__all__ = ["MujocoCell"]
