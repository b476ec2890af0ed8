"""A Pinocchio model handed to the compiled kernel (private).

The Python layer builds every arm's model with Pinocchio (a URDF chain or a DH table,
the base folded in, the tool and link frames added; the carried object and its sliding
grasps on the leader's, :mod:`dualarm_qp.task.carry`). The kernel cannot take a
``pinocchio.Model`` object (Pinocchio's Python objects and the kernel's bindings do not
mix), so it is handed the model's description as arrays: per joint its parent, kind,
axis and placement; per frame its parent joint and placement. From these it rebuilds the
same model with Pinocchio's C++ headers (:class:`dualarm_qp._kernel.Chain`), with the
same joint and frame indices, and computes the forward kinematics and the frame
Jacobians there. A placement edited on the Python model afterwards (a new base, tool or
grasp path) is copied with :func:`set_joint_placement` and :func:`set_frame_placement`.

Importing this module checks that the installed Pinocchio is the release the kernel was
compiled with (:func:`dualarm_qp._compiled.check_pinocchio`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin

from .._compiled import check_pinocchio, kernel
from ..errors import InvalidInputError

#: Pinocchio's one-dof joints, by short name, as the kernel's joint kinds.
JOINT_KINDS = {"JointModelRX": 0, "JointModelRY": 1, "JointModelRZ": 2,
               "JointModelRevoluteUnaligned": 3, "JointModelPX": 4, "JointModelPY": 5,
               "JointModelPZ": 6, "JointModelPrismaticUnaligned": 7}
_UNALIGNED = frozenset({"JointModelRevoluteUnaligned", "JointModelPrismaticUnaligned"})

check_pinocchio(str(pin.__version__))


def compiled_chain(model: Any) -> kernel.Chain:
    """Return the kernel's copy of ``model`` (a ``pinocchio.Model`` of one-dof joints).

    Joint ``j`` and frame ``i`` of the copy are joint ``j`` and frame ``i`` of ``model``.

    Raises
    ------
    InvalidInputError
        A joint that is not one of :data:`JOINT_KINDS` with one coordinate.
    """
    n = model.njoints - 1
    parents: list[int] = []
    kinds: list[int] = []
    axes = np.zeros((n, 3))
    placements = np.empty((4 * n, 4))
    for j in range(1, model.njoints):
        joint = model.joints[j]
        kind = joint.shortname()
        if kind not in JOINT_KINDS or joint.nq != 1 or joint.nv != 1:
            raise InvalidInputError(
                f"{model.name or 'model'}: joint {model.names[j]!r} is {kind}; the kinematics "
                f"take one-dof joints only ({', '.join(sorted(JOINT_KINDS))})")
        if kind in _UNALIGNED:
            axes[j - 1] = joint.extract().axis
        parents.append(int(model.parents[j]))
        kinds.append(JOINT_KINDS[kind])
        placements[4 * j - 4:4 * j] = model.jointPlacements[j].homogeneous
    frames = list(model.frames)[1:]  # frame 0, the universe, is the copy's own frame 0
    frame_parents = [int(f.parentJoint) for f in frames]
    frame_placements = np.empty((4 * len(frames), 4))
    for i, frame in enumerate(frames):
        frame_placements[4 * i:4 * i + 4] = frame.placement.homogeneous
    chain = kernel.Chain(parents, kinds, axes, placements, frame_parents, frame_placements)
    chain.set_frame_placement(0, model.frames[0].placement.homogeneous)
    return chain


def set_joint_placement(model: Any, chain: kernel.Chain, joint: int, placement: Any) -> None:
    """Set joint ``joint``'s placement (a ``pinocchio.SE3``) in ``model`` and its copy."""
    model.jointPlacements[joint] = placement
    chain.set_joint_placement(joint, placement.homogeneous)


def set_frame_placement(model: Any, chain: kernel.Chain, frame: int, placement: Any) -> None:
    """Set frame ``frame``'s placement (a ``pinocchio.SE3``) in ``model`` and its copy."""
    model.frames[frame].placement = placement
    chain.set_frame_placement(frame, placement.homogeneous)


__all__ = ["JOINT_KINDS", "compiled_chain", "set_frame_placement", "set_joint_placement"]
