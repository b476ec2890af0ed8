"""An arm's Pinocchio model: one chain of revolute joints, with the frames the arm adds.

Whatever the source of a model (a URDF chain, a robot of example-robot-data, a DH
table), :class:`~dualarm_qp.kinematics.arm.SerialArm` holds a copy with a frame at the
base (frame 0), one on each joint and the flange; a continuous joint becomes a revolute
joint of range +-inf (:mod:`~dualarm_qp.kinematics.continuous`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from ..errors import InvalidInputError
from .continuous import is_continuous, one_angle_model

FloatArray = NDArray[np.float64]

#: Pinocchio joint kinds an arm may have: revolute, one coordinate (nq = nv = 1).
REVOLUTE_JOINTS = frozenset({"JointModelRX", "JointModelRY", "JointModelRZ",
                             "JointModelRevoluteUnaligned"})
#: Limits at or beyond this magnitude mean "no limit" (Pinocchio's default is DBL_MAX).
NO_LIMIT = 1e300
#: Names of the frames an arm adds to a model.
BASE_FRAME, LINK_FRAME, TOOL_FRAME = "dualarm_base", "dualarm_link", "dualarm_tool"


def se3(T: FloatArray) -> Any:
    """Convert a 4x4 pose to a ``pinocchio.SE3``."""
    return pin.SE3(np.array(T[:3, :3]), np.array(T[:3, 3]))


def chain_model(source: Any, tip: str | None, name: str) -> tuple[Any, list[int], int]:
    """Check that ``source`` is one chain of revolute joints and copy it with our frames.

    Returns the copy, the ids of its frames 0..n (the base, then one frame on each
    joint) and the id of the flange frame ``tip``.
    """
    label = source.name or name
    if source.njoints < 2:
        raise InvalidInputError(f"{label}: the model has no joints")
    for j in range(1, source.njoints):
        if source.parents[j] != j - 1:
            raise InvalidInputError(
                f"{label}: not a single chain: the parent of joint {source.names[j]!r} is "
                f"{source.names[source.parents[j]]!r}, not the joint before it")
        check_revolute(source, j, label)
    model = pin.Model(one_angle_model(source))  # a continuous joint: one angle, +-inf
    last = model.njoints - 1
    if tip is None:
        flange = model.addFrame(pin.Frame(f"{LINK_FRAME}_flange", last, 0, pin.SE3.Identity(),
                                          pin.FrameType.OP_FRAME))
    else:
        flange = frame_id(model, tip, "tip", label)
        if model.frames[flange].parentJoint != last:
            raise InvalidInputError(
                f"{label}: joint {model.names[last]!r} does not move the tip frame {tip!r}; "
                "the chain must end at the tip")
    links = [model.addFrame(pin.Frame(BASE_FRAME, 0, 0, pin.SE3.Identity(),
                                      pin.FrameType.OP_FRAME))]
    for j in range(1, model.njoints):
        links.append(model.addFrame(pin.Frame(f"{LINK_FRAME}{j}", j, 0, pin.SE3.Identity(),
                                              pin.FrameType.OP_FRAME)))
    return model, links, flange


def check_revolute(model: Any, j: int, label: str) -> None:
    """Raise :class:`InvalidInputError` unless joint ``j`` of ``model`` turns about one axis.

    A revolute joint with one coordinate, or a continuous one (which the arm makes a
    revolute joint of range +-inf, :mod:`~dualarm_qp.kinematics.continuous`).
    """
    joint = model.joints[j]
    kind = joint.shortname()
    if (kind in REVOLUTE_JOINTS and joint.nq == 1 and joint.nv == 1) or is_continuous(joint):
        return
    what = kind.removeprefix("JointModel")
    if kind.startswith(("JointModelP", "JointModelPrismatic")):
        what = "prismatic"
    raise InvalidInputError(
        f"{label}: joint {model.names[j]!r} is {what}; an arm has revolute (or continuous) "
        "joints only")


def frame_id(model: Any, frame: str, what: str, label: str) -> int:
    """Index of the frame named ``frame`` (a link's body frame first), or a clear error."""
    ids = [i for i, f in enumerate(model.frames) if f.name == frame]
    if not ids:
        links = sorted(f.name for f in model.frames if f.type == pin.FrameType.BODY)
        shown = ", ".join(links[:40]) + (", ..." if len(links) > 40 else "")
        raise InvalidInputError(f"{label}: {what} frame {frame!r} not found (links: {shown})")
    body = [i for i in ids if model.frames[i].type == pin.FrameType.BODY]
    return (body or ids)[0]


def model_limits(model: Any) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Read the model's joint ranges and speed limits; huge values (or zero speed): none."""
    lo = np.array(model.lowerPositionLimit, dtype=np.float64)
    hi = np.array(model.upperPositionLimit, dtype=np.float64)
    vel = np.array(model.velocityLimit, dtype=np.float64)
    lo[lo <= -NO_LIMIT] = -np.inf
    hi[hi >= NO_LIMIT] = np.inf
    vel[(vel <= 0.0) | (vel >= NO_LIMIT)] = np.inf
    return lo, hi, vel


def trans(x: float, y: float, z: float) -> FloatArray:
    """Return the 4x4 translation by ``(x, y, z)`` [m]."""
    T = np.eye(4)
    T[:3, 3] = (x, y, z)
    return T


def rot(R: FloatArray) -> FloatArray:
    """Return the 4x4 rotation ``R``."""
    T = np.eye(4)
    T[:3, :3] = R
    return T


__all__ = ["BASE_FRAME", "LINK_FRAME", "NO_LIMIT", "REVOLUTE_JOINTS", "TOOL_FRAME",
           "chain_model", "check_revolute", "frame_id", "model_limits", "rot", "se3", "trans"]
