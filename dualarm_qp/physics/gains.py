"""The joint servos' gains: per joint, from the arm's own inertia.

One gain for every joint of every arm cannot suit them all: a UR10's shoulder moves
about 90 times the inertia of a wrist, so a gain stiff enough for the shoulder makes
the wrist ring at the edge of what the integrator holds, and one the wrist takes leaves
the shoulder soft. Each joint ``i`` is given instead the gains of a second-order
system of one natural frequency ``omega_n`` and one damping ratio ``zeta``:

    kp_i = M_ii omega_n^2,        kv_i = 2 zeta M_ii omega_n,

with ``M_ii`` the diagonal of the arm's joint-space inertia at the start (MuJoCo's
``M``, the links' inertia and the joint's armature, the rotor's reflected inertia).

The frequency is ``physics.servo_frequency`` (default :data:`SERVO_FREQUENCY`, 40 Hz),
lowered where the integrator would not hold it: MuJoCo integrates the servo's spring
explicitly (its damping implicitly), which is stable while ``omega h < 2`` for every
mode, ``h`` the substep. The joints are coupled (``M`` is not diagonal), so the highest
mode of ``M^-1 K`` with ``K = diag(M_ii) omega_n^2`` is ``omega_n sqrt(lambda)``,
``lambda`` the largest eigenvalue of ``M^-1 diag(M)`` (1 for uncoupled joints; up to 18
for the Panda's wrist on the shipped files). The frequency is taken as the file's, or
:data:`INTEGRATOR_MARGIN` ``/ (h sqrt(lambda))`` if that is lower (half the stability
bound), per arm.

A file that states ``physics.kp`` or ``physics.kv`` sets that gain to its value on every
joint, as before this rule; the other gain follows the rule.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .settings import SERVO_FREQUENCY, PhysicsSettings

FloatArray = NDArray[np.float64]

#: Largest ``omega h`` of an arm's highest servo mode: half the explicit bound of 2.
INTEGRATOR_MARGIN = 1.0


@dataclass(frozen=True)
class ServoGains:
    """Each arm joint's servo gains (the leader's joints first).

    Attributes
    ----------
    kp : ndarray, shape (n,)
        Position gains [N m/rad].
    kv : ndarray, shape (n,)
        Velocity gains [N m s/rad].
    inertia : ndarray, shape (n,)
        ``M_ii`` at the start [kg m^2], armature included.
    omega : dict of str to float
        Each arm's natural frequency [rad/s] (after the integrator's bound).
    coupling : dict of str to float
        Each arm's ``lambda``, the largest eigenvalue of ``M^-1 diag(M)``.
    limited : list of str
        The arms whose frequency the integrator's bound lowered.
    """

    kp: FloatArray
    kv: FloatArray
    inertia: FloatArray
    omega: dict[str, float]
    coupling: dict[str, float]
    limited: list[str]

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready (SI)."""
        return {"kp_N_m_rad": self.kp.tolist(), "kv_N_m_s_rad": self.kv.tolist(),
                "inertia_kg_m2": self.inertia.tolist(),
                "omega_rad_s": dict(self.omega), "coupling": dict(self.coupling),
                "frequency_lowered_for": list(self.limited)}


def servo_gains(M: FloatArray, arms: dict[str, FloatArray], settings: PhysicsSettings,
                substep: float) -> ServoGains:
    """Return each arm joint's gains from the joint-space inertia ``M`` (see the module).

    Parameters
    ----------
    M : ndarray, shape (nv, nv)
        MuJoCo's joint-space inertia at the start (armature included).
    arms : dict of str to ndarray of int
        The dofs of ``"leader"`` and ``"follower"`` in ``M``.
    settings : PhysicsSettings
        ``servo_frequency`` [Hz], ``damping_ratio``, and ``kp``, ``kv`` if the file
        stated them (None: the rule).
    substep : float
        MuJoCo's time step ``h`` [s].
    """
    kp, kv, inertia = [], [], []
    omega, coupling, limited = {}, {}, []
    wanted = 2.0 * math.pi * settings.servo_frequency
    for role in ("leader", "follower"):
        dofs = np.asarray(arms[role], dtype=int)
        Ma = M[np.ix_(dofs, dofs)]
        d = np.diag(Ma).copy()
        lam = 1.0
        if d.size:
            lam = float(np.max(np.linalg.eigvals(np.linalg.solve(Ma, np.diag(d))).real))
        w = min(wanted, INTEGRATOR_MARGIN / (substep * math.sqrt(max(lam, 1.0))))
        if w < wanted:
            limited.append(role)
        omega[role], coupling[role] = w, lam
        kp.append(d * w * w if settings.kp is None else np.full(d.size, settings.kp))
        kv.append(2.0 * settings.damping_ratio * d * w if settings.kv is None
                  else np.full(d.size, settings.kv))
        inertia.append(d)
    return ServoGains(np.concatenate(kp), np.concatenate(kv), np.concatenate(inertia),
                      omega, coupling, limited)


def set_gains(model: Any, gains: ServoGains, servo: str) -> None:
    """Write ``gains`` into MuJoCo's actuators (:func:`~.mjcf.build_mjcf`'s order).

    A ``position`` servo has two actuators per joint (position ``kp``, velocity
    ``kv``), a ``velocity`` servo one (``kv``).
    """
    n = gains.kv.size
    if servo == "position":
        p, v = np.arange(0, 2 * n, 2), np.arange(1, 2 * n, 2)
        model.actuator_gainprm[p, 0] = gains.kp
        model.actuator_biasprm[p, 1] = -gains.kp
    else:
        v = np.arange(n)
    model.actuator_gainprm[v, 0] = gains.kv
    model.actuator_biasprm[v, 2] = -gains.kv


def unstable_gains_advice(st: PhysicsSettings, g: ServoGains | None, timestep: float) -> str:
    """Return what a divergence message says of the servo gains, and what to change.

    ``st`` the settings, ``g`` the gains set (None: not yet), ``timestep`` the substep [s].
    """
    h = f"{timestep * 1e3:.3g} ms"
    if st.kp is None and st.kv is None:
        span = "" if g is None else (f"; kp {g.kp.min():.3g}..{g.kp.max():.3g} N m/rad, "
                                     f"kv {g.kv.min():.3g}..{g.kv.max():.3g} N m s/rad")
        return (f"The servo gains (each joint's from its inertia at "
                f"{st.servo_frequency:g} Hz, damping ratio {st.damping_ratio:g}{span}) "
                "are unstable with armature "
                f"{st.armature:g} kg m^2 at substeps of {h}: lower "
                "physics.servo_frequency, or raise physics.armature")
    given = ", ".join(f"{k} {v:g}" for k, v in (("kp", st.kp), ("kv", st.kv))
                      if v is not None and (k == "kv" or st.servo == "position"))
    return (f"The servo gains ({given}, the same on every joint) are unstable with "
            f"armature {st.armature:g} kg m^2 at substeps of {h}: lower physics.kp "
            "(or physics.kv), leave them out (each joint's gains from its inertia), "
            "or raise physics.armature")


__all__ = ["INTEGRATOR_MARGIN", "SERVO_FREQUENCY", "ServoGains", "servo_gains", "set_gains",
           "unstable_gains_advice"]
