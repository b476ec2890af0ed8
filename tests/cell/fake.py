"""A cell for tests: two arms that follow the rates sent exactly (explicit Euler).

It can stop updating its state after a given sample (a stalled driver, for the
watchdog), raise KeyboardInterrupt while waiting for a given sample (Ctrl-C), and
records every send and the cell's time it came at.
"""

from __future__ import annotations

import numpy as np

from dualarm_qp.cell.base import CellError, Reading


class KinematicCell:
    kind = "kinematic"
    between = "held"

    def __init__(self, q_l, q_f, dt, *, freeze_after=None, interrupt_at=None, fail_at=None,
                 offset=0.0):
        self.q_l = np.asarray(q_l, dtype=float) + offset
        self.q_f = np.asarray(q_f, dtype=float).copy()
        self.dt = dt
        self.t = 0.0
        self.v = (np.zeros(self.q_l.size), np.zeros(self.q_f.size))
        self.sends: list[np.ndarray] = []
        self.send_times: list[float] = []
        self.freeze_after = freeze_after
        self.interrupt_at = interrupt_at
        self.fail_at = fail_at
        self.reading = None
        self.closed = False

    def open(self):
        self.reading = Reading(self.t, self.q_l.copy(), self.q_f.copy())
        return self.reading

    def read(self):
        return self.reading

    def now(self):
        return self.t

    def send(self, ql_dot, qf_dot):
        self.v = (np.asarray(ql_dot, dtype=float).copy(), np.asarray(qf_dot, dtype=float).copy())
        self.sends.append(np.r_[self.v[0], self.v[1]])
        self.send_times.append(self.t)

    def wait_until(self, t):
        k = round(t / self.dt)
        if self.interrupt_at is not None and k == self.interrupt_at:
            self.interrupt_at = None
            raise KeyboardInterrupt("SIGINT")
        if self.fail_at is not None and k == self.fail_at:
            self.fail_at = None
            raise CellError("the connection to the robot was lost")
        while self.t < t - 1e-12:
            self.q_l = self.q_l + self.dt * self.v[0]
            self.q_f = self.q_f + self.dt * self.v[1]
            self.t += self.dt
            if self.freeze_after is None or round(self.t / self.dt) <= self.freeze_after:
                self.reading = Reading(self.t, self.q_l.copy(), self.q_f.copy())

    def close(self):
        self.closed = True
