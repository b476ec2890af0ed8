"""A compliant follower: its grasp closure with force feedback where the grasp holds.

Two position-controlled arms holding one rigid object form a closed chain: the split
of the load between them is set by their servos' stiffness and by whatever the
kinematics get slightly wrong (a weld's deflection, a base a few millimetres off, a
late measurement), not by the plan's statics. The closure task (``GraspClosureTask``:
``J_f qf_dot - J_t x = K e_c``) makes it worse: in the directions the grasp holds, the
hand cannot move on the object, so any closure error the kinematics see there is not
a gap to close but a force to build.

:class:`ComplianceTask` is the closure task with **admittance** in those directions.
Its six rows are the closure's, with the right-hand side

    b = K P_free e_c + v,        v = -P_held [K_f dw_f; K_m dw_m],

``P_free`` the projection onto the grasp's free twists (the slide and the spin of a
sliding grasp, all but the push of a support), ``P_held = I - P_free``, and ``dw`` the
follower's **wrench error**, filtered (first order, time constant ``filter_time``):

* a grasp (Case 1): the follower's part of the measured pair that the plan's split
  rule (the minimum norm, :mod:`dualarm_qp.task.loads`) does not give it, i.e. its
  internal (squeeze) wrench, whose planned value is zero. At rest the hands carry the
  weight, and the follower then carries exactly the plan's share; moving, the object's
  inertia is split by the same rule;
* a support (Case 2): the normal force against the support line's ``h`` (Eq. 10),
  along the normal.

The hand yields to a force it applies beyond its share (``v`` against ``dw``) at
``K_f`` [m/(N s)] and ``K_m`` [rad/(N m s)]. The rows are equalities, as the closure's
(the task takes the standard closure's place in the step): every hard limit of the step
still holds. The measured wrenches reach the task through a :class:`WrenchMeasurement`
that the plant updates with each state it hands the controller (with the same delay);
without a reading the task refuses to step (:class:`NoWrenchReadingError`).
docs/physics.md states the gains' stability condition and the measured numbers.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, cast

import numpy as np
from numpy.typing import NDArray

from .._compiled import kernel
from ..control.measured import HandReading
from ..errors import InvalidInputError
from ..step.tasks import GraspClosureTask
from ..task.hands import hand_statics
from ..task.loads import ObjectLoad, wrench_space
from .measure import internal_force

if TYPE_CHECKING:
    from ..step.context import StepContext

FloatArray = NDArray[np.float64]


class NoWrenchReadingError(InvalidInputError):
    """A compliant follower stepped without a reading of the hands' wrenches."""


@dataclass(frozen=True)
class ComplianceGains:
    """The admittance's gains (SI).

    Attributes
    ----------
    force_gain : float
        ``K_f`` [m/(N s)]: the hand's speed per newton beyond its share.
    moment_gain : float
        ``K_m`` [rad/(N m s)]: its turn rate per newton metre.
    filter_time : float
        Time constant of the first-order filter on the measured wrenches [s] (0: none).
    """

    force_gain: float = 2e-4
    moment_gain: float = 2e-3
    filter_time: float = 0.02

    def __post_init__(self) -> None:
        for key in ("force_gain", "moment_gain", "filter_time"):
            value = float(getattr(self, key))
            if not (math.isfinite(value) and value >= 0.0):
                raise InvalidInputError(f"compliance {key} must be a finite number >= 0, "
                                        f"got {value}")

    def as_dict(self) -> dict[str, float]:
        """JSON-ready (SI)."""
        return {"force_gain_m_N_s": self.force_gain,
                "moment_gain_rad_N_m_s": self.moment_gain,
                "filter_time_s": self.filter_time}


class WrenchMeasurement:
    """The hands' measured wrenches, filtered: what a plant updates and the task reads.

    Parameters
    ----------
    filter_time : float
        Time constant of the first-order filter [s] (0: the latest reading as it is).
    """

    def __init__(self, filter_time: float = 0.0) -> None:
        self.filter_time = float(filter_time)
        self.leader: FloatArray | None = None
        self.follower: FloatArray | None = None
        self.updates = 0

    def reset(self) -> None:
        """Forget every reading (a new run)."""
        self.leader = self.follower = None
        self.updates = 0

    def update(self, reading: HandReading, dt: float) -> None:
        """Take the reading handed with a state, ``dt`` [s] after the last one."""
        w_l = np.asarray(reading.leader, dtype=float)
        w_f = np.asarray(reading.follower, dtype=float)
        if self.leader is None or self.follower is None or self.filter_time <= 0.0:
            self.leader, self.follower = w_l.copy(), w_f.copy()
        else:
            a = 1.0 - math.exp(-dt / self.filter_time)
            self.leader = self.leader + a * (w_l - self.leader)
            self.follower = self.follower + a * (w_f - self.follower)
        self.updates += 1


class ComplianceTask(GraspClosureTask):
    """The grasp closure with admittance in the directions the grasp holds (module).

    Parameters
    ----------
    gain : float
        The closure's feedback gain ``K`` [1/s] (``controller.correction_gain``), kept
        in the grasp's free directions.
    load : ObjectLoad
        The object's mass, mass centre and gravity (a support's push needs them).
    gains : ComplianceGains
        ``K_f``, ``K_m`` and the filter.
    measurement : WrenchMeasurement, optional
        Where the plant leaves its readings (default: a new one, ``filter_time`` of
        ``gains``).
    exact_orientation : bool
        As :class:`~dualarm_qp.step.tasks.GraspClosureTask`.
    """

    name = "compliant grasp closure"

    def __init__(self, gain: float, load: ObjectLoad, gains: ComplianceGains, *,
                 measurement: WrenchMeasurement | None = None,
                 exact_orientation: bool = False) -> None:
        super().__init__(gain, exact_orientation=exact_orientation)
        self.load = load
        self.gains = gains
        self.measurement = (WrenchMeasurement(gains.filter_time) if measurement is None
                            else measurement)
        #: The admittance's twist of the last step [m/s, rad/s], world (for reports).
        self.twist = np.zeros(6)

    def __reduce__(self) -> tuple[Any, ...]:
        return (_compliance, (self.gain, self.load, self.gains, self.exact_orientation))

    def equality(self, ctx: object) -> Any:
        """Return the closure's rows at ``ctx`` (a ``StepContext``), admittance added."""
        m = self.measurement
        if m.leader is None or m.follower is None:
            raise NoWrenchReadingError(
                "the compliant follower has no reading of the hands' wrenches: it needs a "
                "plant that measures them (dualarm_qp.physics.plant.MujocoPlant, or a "
                "cell's force/torque sensors) to update its measurement each sample")
        eq = super().equality(ctx)
        step = cast("StepContext", ctx)
        task, state = dataclasses.replace(step.task, load=self.load), step.state
        hands, _ = hand_statics(task, state.q_l, state.sigma, state.sigma_leader)
        free = _orthonormal(hands[1].free)
        P_free = free @ free.T
        error = self._wrench_error(hands, m.leader, m.follower)
        v = -np.r_[self.gains.force_gain * error[:3], self.gains.moment_gain * error[3:]]
        self.twist = v - P_free @ v
        b = self.gain * (P_free @ np.asarray(step.closure_error)) + self.twist
        return kernel.Equality(np.asarray(eq.A), b, list(eq.names))

    def _wrench_error(self, hands: list[Any], w_l: FloatArray, w_f: FloatArray
                      ) -> FloatArray:
        """Return the follower's wrench beyond its share (module docstring), world."""
        follower = hands[1]
        if follower.wrench is not None:  # a support: its push against the support line's
            normal = follower.wrench[:3] / np.linalg.norm(follower.wrench[:3])
            excess = float(w_f[:3] @ normal) - float(follower.wrench[:3] @ normal)
            return np.r_[excess * normal, np.zeros(3)]
        spaces = (wrench_space(hands[0]), wrench_space(follower))
        _, pair = internal_force((hands[0].point, follower.point), spaces, (w_l, w_f))
        return np.asarray(pair[1], dtype=float)


def _orthonormal(free: FloatArray) -> FloatArray:
    """Return an orthonormal basis (6, k) of the columns of ``free`` (6, k)."""
    if free.shape[1] == 0:
        return np.zeros((6, 0))
    q, r = np.linalg.qr(free)
    keep = np.abs(np.diag(r)) > 1e-12
    return np.asarray(q[:, keep])


def _compliance(gain: float, load: ObjectLoad, gains: ComplianceGains,
                exact_orientation: bool) -> ComplianceTask:
    return ComplianceTask(gain, load, gains, exact_orientation=exact_orientation)


__all__ = ["ComplianceGains", "ComplianceTask", "NoWrenchReadingError", "WrenchMeasurement"]
