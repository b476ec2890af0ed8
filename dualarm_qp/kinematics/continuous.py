"""Continuous joints as revolute joints with one angle.

A URDF ``continuous`` joint turns without end. Pinocchio models it with two coordinates,
``(cos q, sin q)``, and one velocity (``JointModelRUBX`` .. ``RUBZ``,
``JointModelRevoluteUnboundedUnaligned``). Every arm of this library has one angle per
joint, everywhere above the model layer (the step's variables, the ranges, the files,
``trajectory.csv``), so :func:`one_angle_model` rebuilds such a model with each
continuous joint replaced by a revolute joint (``JointModelRX`` .. ``RZ``,
``JointModelRevoluteUnaligned``) about the same axis, at the same placement, with the
same name, inertia, effort and speed limits, and with the range ``(-inf, inf)``.

What that means: the joint's coordinate is its angle [rad], not wrapped. ``q`` and
``q + 2 pi`` give the same pose but are different values of the coordinate (as for a
revolute joint with a range wider than a turn); with no range there is no range limit,
no range end to brake before, and no range middle to centre on. A range of the user's
(``q_min`` / ``q_max``) makes it an ordinary revolute joint with that range.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin

#: Pinocchio's continuous (unbounded revolute) joints, by short name, and the revolute
#: joint about the same axis that replaces each (None: an unaligned axis).
CONTINUOUS_JOINTS: dict[str, Any] = {
    "JointModelRUBX": pin.JointModelRX,
    "JointModelRUBY": pin.JointModelRY,
    "JointModelRUBZ": pin.JointModelRZ,
    "JointModelRevoluteUnboundedUnaligned": None,
}

#: The model's arrays with one entry per velocity coordinate: copied as they are
#: (a continuous joint has one velocity, as its replacement has).
_PER_VELOCITY = ("effortLimit", "lowerEffortLimit", "upperEffortLimit", "velocityLimit",
                 "lowerVelocityLimit", "upperVelocityLimit", "friction", "damping",
                 "armature", "rotorInertia", "rotorGearRatio", "lowerDryFrictionLimit",
                 "upperDryFrictionLimit")


def is_continuous(joint: Any) -> bool:
    """Whether a Pinocchio joint model is a continuous joint (two coordinates, one angle)."""
    return str(joint.shortname()) in CONTINUOUS_JOINTS


def continuous_joints(model: Any) -> list[int]:
    """Return the indices of the continuous joints of ``model`` (``pinocchio.Model``)."""
    return [j for j in range(1, model.njoints) if is_continuous(model.joints[j])]


def one_angle_model(source: Any) -> Any:
    """Return ``source`` with every continuous joint made a revolute joint of range +-inf.

    Parameters
    ----------
    source : pinocchio.Model
        Any model; not changed.

    Returns
    -------
    pinocchio.Model
        ``source`` itself when it has no continuous joint, else a new model with the
        same joints (each continuous one replaced, see the module docstring), frames
        and inertias, in the same order and with the same indices. Its configuration
        has one coordinate fewer per continuous joint; its velocity is the same.
    """
    replaced = continuous_joints(source)
    if not replaced:
        return source
    axes = _axes(source, replaced)
    model = pin.Model()
    model.name = source.name
    lower: list[float] = []
    upper: list[float] = []
    unbounded = float(np.finfo(np.float64).max)  # Pinocchio's "no limit"
    for j in range(1, source.njoints):
        joint = source.joints[j]
        if j in axes:
            kind = CONTINUOUS_JOINTS[str(joint.shortname())]
            joint = (pin.JointModelRevoluteUnaligned(axes[j]) if kind is None else kind())
            lower.append(-unbounded)
            upper.append(unbounded)
        else:
            q = slice(joint.idx_q, joint.idx_q + joint.nq)
            lower += list(source.lowerPositionLimit[q])
            upper += list(source.upperPositionLimit[q])
        model.addJoint(int(source.parents[j]), joint, source.jointPlacements[j],
                       str(source.names[j]))
        model.inertias[j] = source.inertias[j]
    for frame in list(source.frames)[1:]:  # frame 0 is the universe, in both
        model.addFrame(pin.Frame(frame), False)  # the joints carry the inertias already
    model.lowerPositionLimit = np.array(lower)
    model.upperPositionLimit = np.array(upper)
    for name in _PER_VELOCITY:
        if hasattr(source, name):
            setattr(model, name, np.array(getattr(source, name), dtype=np.float64))
    return model


def _axes(model: Any, joints: list[int]) -> dict[int, Any]:
    """Return the unit axis of each of ``joints`` in its joint frame (its motion subspace)."""
    data = model.createData()
    pin.forwardKinematics(model, data, pin.neutral(model))
    return {j: np.array(np.asarray(data.joints[j].S).reshape(6)[3:], dtype=np.float64)
            for j in joints}


__all__ = ["CONTINUOUS_JOINTS", "continuous_joints", "is_continuous", "one_angle_model"]
