"""The ``physics:`` section of an experiment file: servos, thresholds, default object.

The defaults, as written in a file with ``units: {length: mm, angle: rad, time: s}``
(in a file with degrees, ``rotation_max`` is 2.86 for the same 0.05 rad)::

    physics:
      servo: position          # position (PD about the commanded motion) or velocity
      reference: measured      # the position reference leaks towards the measured
                               # joints (measured) or only integrates (integrated)
      reference_time: 0.03     # time unit (here s): the leak's time constant
      servo_frequency: 40      # Hz: each joint's servo is a second-order system of this
                               # natural frequency on the arm's own inertia (gains.py)
      damping_ratio: 1.0       # of that system
      kp:                      # N m/rad: one position gain for every joint instead (SI)
      kv:                      # N m s/rad: one velocity gain for every joint instead
      armature: 0.05           # kg m^2, rotor inertia added to every arm joint
      delay: 0                 # closed loop: the controller sees the measurement this
                               # many samples late (true: 1, false: 0)
      predict: true            # with delay: the late measurement brought forward by the
                               # commands applied since
      contacts: obstacles      # which geoms touch: obstacles (with the arms, the object),
                               # all (also arm-arm, arm-object) or none
      geometry: meshes         # a URDF arm's links: its collision meshes (convex hulls)
                               # and primitives, or the project's capsules
      object_mass: 3           # kg, when the object states no mass
      link_density: 1000       # kg/m^3, links whose model has no inertia
      deviation_max: 10        # length unit (here mm): the object off D(t) -> dropped
      rotation_max: 0.05       # angle unit (here rad): the object turned off D(t) -> dropped
      slip_max: 5              # length unit (here mm): a grasp off its commanded place -> slipped
      squeeze_max: 20          # N: internal force above the rigid replay's -> squeezed
      torque_ratio_max: 1.0    # share of the joint torque limit -> torque
      tau_max: {leader: [...], follower: [...]}   # N m, 1 value or 1 per joint, .inf: none;
                               # default: the arm's tau_max, else the URDF's effort

Every key is optional; the defaults are those above (docs/physics.md says why). The
section is validated with the rest of the file: an unknown key or a bad value is a
:class:`~dualarm_qp.errors.ConfigError` naming the file and ``physics.<key>``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..experiments.config_physics import ComplianceSpec, PhysicsSpec
from .compliance import ComplianceGains

FloatArray = NDArray[np.float64]

#: Servo kinds: ``position`` (PD about the integrated command, velocity feed-forward)
#: or ``velocity`` (damping about the commanded rate only).
SERVOS = ("position", "velocity")

#: The closed loop's position reference: pulled towards the measured joints, or the
#: commands integrated since the start only.
REFERENCES = ("measured", "integrated")

#: Which contacts are simulated: ``obstacles`` (the arms' links and the object against
#: the obstacles; arm-arm and arm-object clearance is the collision module's, measured on
#: the same conservative capsules), ``all`` (every pair but those excluded) or ``none``.
CONTACTS = ("obstacles", "all", "none")

#: The links' geometry in MuJoCo: a URDF arm's collision ``meshes`` (convex hulls and
#: primitives, :mod:`~dualarm_qp.physics.meshes`) or the project's ``capsules``. A DH
#: arm has capsules either way.
GEOMETRIES = ("meshes", "capsules")

#: MuJoCo's time step [s]: the controller's ``dt`` is cut into substeps of at most this.
SUBSTEP = 1e-3

#: Default natural frequency of the joint servos [Hz] (:mod:`~dualarm_qp.physics.gains`).
SERVO_FREQUENCY = 40.0

@dataclass(frozen=True)
class PhysicsSettings:
    """The physics check's settings in SI units (built from :class:`PhysicsSpec`).

    Attributes
    ----------
    servo : {"position", "velocity"}
        Joint servo kind (:data:`SERVOS`).
    reference : {"measured", "integrated"}
        Closed loop, position servo: the position reference integrates the commanded
        rates and is pulled towards the measured joints (``measured``) or not
        (``integrated``: the commands integrated since the start).
    reference_time : float
        Time constant of that pull [s] (default 0.03 s).
    servo_frequency : float
        Natural frequency of every joint's servo on the arm's own inertia [Hz]
        (:mod:`~dualarm_qp.physics.gains`; lowered where the integrator needs it).
    damping_ratio : float
        Damping ratio of every joint's servo.
    kp : float or None
        One position gain for every joint [N m/rad] (position servo only); None: each
        joint's from its inertia.
    kv : float or None
        One velocity gain for every joint [N m s/rad]; None: each joint's from its
        inertia.
    armature : float
        Rotor inertia added to every arm joint [kg m^2].
    delay : int
        Closed loop: the controller is handed the measurement this many samples late.
    predict : bool
        With ``delay``: the late joints and grasps are brought forward by the commands
        applied since (:mod:`dualarm_qp.control.predict`); False: handed as measured.
    contacts : {"obstacles", "all", "none"}
        Which contacts are simulated (:data:`CONTACTS`).
    geometry : {"meshes", "capsules"}
        The links' geometry of a URDF arm (:data:`GEOMETRIES`); DH arms: capsules.
    object_mass : float
        Mass of an object whose file states none [kg].
    link_density : float
        Density of the capsules that give a link without inertia its mass [kg/m^3].
    deviation_max : float
        Largest deviation of the object from ``D(t)`` before the verdict is
        ``dropped`` [m] (default 10 mm).
    rotation_max : float
        Largest rotation of the object off ``D(t)`` before the verdict is ``dropped``
        [rad] (default 0.05 rad, about 3 deg).
    slip_max : float
        Largest slip of a grasp before the verdict is ``slipped`` [m] (default 5 mm).
    squeeze_max : float
        Largest internal force above the rigid replay's before the verdict is
        ``squeezed`` [N].
    torque_ratio_max : float
        Largest share of a joint torque limit before the verdict is ``torque``.
    tau_max : dict of str to ndarray or None
        Torque limits [N m] per arm (``"leader"``, ``"follower"``) given in the file;
        None: the arm's own ``tau_max``, else its model's (a URDF's ``effort``), if any.
    compliance : ComplianceGains or None
        The closed loop's follower is compliant with these gains
        (:mod:`dualarm_qp.physics.compliance`); None: the standard grasp closure.
    base_error : ndarray, shape (6,), optional
        The simulated follower's base off the model's (a calibration error), in the
        base's own frame: ``[x, y, z]`` [m] and roll, pitch, yaw [rad]
        (``T_base_simulated = T_base Rz(yaw) Ry(pitch) Rx(roll)`` moved by ``[x, y, z]``);
        the controller keeps the model's base.
    """

    servo: str = "position"
    reference: str = "measured"
    reference_time: float = 0.03
    servo_frequency: float = SERVO_FREQUENCY
    damping_ratio: float = 1.0
    kp: float | None = None
    kv: float | None = None
    armature: float = 0.05
    delay: int = 0
    predict: bool = True
    contacts: str = "obstacles"
    geometry: str = "meshes"
    object_mass: float = 3.0
    link_density: float = 1000.0
    deviation_max: float = 0.01
    rotation_max: float = 0.05
    slip_max: float = 0.005
    squeeze_max: float = 20.0
    torque_ratio_max: float = 1.0
    tau_max: dict[str, FloatArray | None] | None = None
    compliance: ComplianceGains | None = None
    base_error: FloatArray | None = None

    def __post_init__(self) -> None:
        if self.base_error is not None:
            error = np.asarray(self.base_error, dtype=float)
            if error.shape != (6,) or not np.all(np.isfinite(error)):
                raise ValueError("base_error must be 6 finite numbers [x, y, z (m), roll, "
                                 f"pitch, yaw (rad)], got {self.base_error!r}")
            object.__setattr__(self, "base_error", error)
        if self.servo not in SERVOS:
            raise ValueError(f"servo must be one of {SERVOS}, got {self.servo!r}")
        if self.reference not in REFERENCES:
            raise ValueError(f"reference must be one of {REFERENCES}, got {self.reference!r}")
        if self.contacts not in CONTACTS:
            raise ValueError(f"contacts must be one of {CONTACTS}, got {self.contacts!r}")
        if self.geometry not in GEOMETRIES:
            raise ValueError(f"geometry must be one of {GEOMETRIES}, got {self.geometry!r}")
        for key in ("servo_frequency", "damping_ratio", "reference_time", "object_mass",
                    "link_density", "deviation_max", "rotation_max", "slip_max",
                    "squeeze_max", "torque_ratio_max"):
            value = float(getattr(self, key))
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{key} must be a finite number > 0, got {value}")
        if isinstance(self.delay, bool) or not (isinstance(self.delay, int) and self.delay >= 0):
            raise ValueError(f"delay must be a whole number of samples >= 0, got {self.delay!r}")
        if self.kv is not None and not (math.isfinite(self.kv) and self.kv > 0):
            raise ValueError(f"kv must be None or a finite number > 0, got {self.kv}")
        if self.kp is not None and not (math.isfinite(self.kp) and self.kp >= 0):
            raise ValueError(f"kp must be None or a finite number >= 0, got {self.kp}")

    @classmethod
    def from_spec(cls, spec: PhysicsSpec, length_scale: float, angle_scale: float = 1.0,
                  time_scale: float = 1.0) -> PhysicsSettings:
        """Convert the file's section to SI.

        ``length_scale`` [m], ``angle_scale`` [rad] and ``time_scale`` [s] per file unit.
        """
        def length(value: float | None, default: float) -> float:
            return default if value is None else value * length_scale

        tau = {role: (None if getattr(spec.tau_max, role) is None
                      else np.asarray(getattr(spec.tau_max, role), dtype=float))
               for role in ("leader", "follower")}
        return cls(servo=spec.servo, reference=spec.reference,
                   reference_time=(0.03 if spec.reference_time is None
                                   else spec.reference_time * time_scale),
                   servo_frequency=spec.servo_frequency,
                   damping_ratio=spec.damping_ratio, kp=spec.kp, kv=spec.kv,
                   armature=spec.armature,
                   delay=spec.delay, predict=spec.predict, contacts=spec.contacts,
                   geometry=spec.geometry, object_mass=spec.object_mass,
                   link_density=spec.link_density,
                   deviation_max=length(spec.deviation_max, 0.01),
                   rotation_max=(0.05 if spec.rotation_max is None
                                 else spec.rotation_max * angle_scale),
                   slip_max=length(spec.slip_max, 0.005), squeeze_max=spec.squeeze_max,
                   torque_ratio_max=spec.torque_ratio_max, tau_max=tau,
                   compliance=_compliance(spec.compliance),
                   base_error=(None if spec.base_error is None else np.r_[
                       np.asarray(spec.base_error.position) * length_scale,
                       np.asarray(spec.base_error.rpy) * angle_scale]))

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready, SI."""
        return {"servo": self.servo, "reference": self.reference,
                "reference_time_s": self.reference_time,
                "servo_frequency_hz": self.servo_frequency,
                "damping_ratio": self.damping_ratio, "kp_N_m_rad": self.kp,
                "kv_N_m_s_rad": self.kv,
                "armature_kg_m2": self.armature, "delay_samples": self.delay,
                "predict": self.predict,
                "contacts": self.contacts, "geometry": self.geometry,
                "substep_s": SUBSTEP, "deviation_max_m": self.deviation_max,
                "rotation_max_rad": self.rotation_max,
                "slip_max_m": self.slip_max, "squeeze_max_N": self.squeeze_max,
                "torque_ratio_max": self.torque_ratio_max,
                "link_density_kg_m3": self.link_density,
                "compliance": None if self.compliance is None else self.compliance.as_dict(),
                "base_error": None if self.base_error is None else {
                    "position_m": self.base_error[:3].tolist(),
                    "rpy_rad": self.base_error[3:].tolist()}}


def _compliance(spec: ComplianceSpec | None) -> ComplianceGains | None:
    """Return the file's compliant follower's gains (None: the standard closure)."""
    if spec is None:
        return None
    return ComplianceGains(spec.force_gain, spec.moment_gain, spec.filter_time)


__all__ = ["CONTACTS", "GEOMETRIES", "REFERENCES", "SERVOS", "SERVO_FREQUENCY", "SUBSTEP",
           "PhysicsSettings"]
