"""Capsules for the links of an arm, each in the frame of the joint that moves it.

The capsules of an arm come as a ``dict[int, Capsule]`` keyed like the rows of
:meth:`SerialArm.link_frames <dualarm_qp.kinematics.SerialArm.link_frames>`: key ``i``
is a capsule in frame ``i``, so ``capsules[i].placed(arm.link_frames(q)[i])`` is the
capsule in the world. Key 0 is the arm's base frame (geometry no joint of the arm
moves); a frame that carries no geometry has no key.

* :func:`urdf_capsules` (and :func:`example_robot_capsules`) read the COLLISION geometry
  of a URDF with Pinocchio (meshes through coal) and fit one capsule per joint
  (:func:`~dualarm_qp.geometry.fit.fit_capsule`) around every collision object of the
  links that joint moves, the links of locked joints below it included (grippers, a
  hand), so that each capsule contains its links' collision geometry.
  :func:`chain_collision_objects` lists those collision objects, each placed in the
  frame of its key (the physics check gives them to MuJoCo as they are).
* :func:`dh_capsules` puts one capsule along each segment between consecutive DH frame
  origins, with given radii (defaults for the PUMA 560 preset:
  :data:`PUMA560_LINK_RADII`).
* :func:`arm_capsules` picks between them from ``SerialArm.source``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from .._validate import as_array
from ..errors import InvalidInputError
from ..kinematics.arm import SerialArm, frame_id
from ..kinematics.robots import RobotModelError, example_robot_urdf, frame_below, urdf_arm
from .capsule_cache import cached_fit
from .fit import geometry_balls
from .shapes import Capsule

#: Radii [m] of the PUMA 560 preset's capsules, one per DH segment (our choice, from the
#: arm's published outline; its lengths come from the paper's Table 1):
#: 1 a sphere on the shoulder (the housing of joints 1-2), 0.12;
#: 2 the upper arm, from the shoulder to the elbow (a2 = 431.8 mm along x, d2 =
#: 149.09 mm sideways: a 457 mm diagonal), 0.10;
#: 3 the elbow (a3 = -20.32 mm), 0.08;
#: 4 the forearm (d4 = 433.07 mm), 0.06;
#: 5 a sphere on the wrist centre, 0.05;
#: 6 the flange (d6 = 56.25 mm), 0.04.
#: The column below the shoulder is not part of the DH table and has no capsule.
PUMA560_LINK_RADII = np.array([0.12, 0.10, 0.08, 0.06, 0.05, 0.04])


def urdf_capsules(file: str | Path, root: str, tip: str, *,
                  package_dirs: Any = None) -> dict[int, Capsule]:
    """Capsules of the arm ``urdf_arm(file, root, tip)``, from the URDF's collision geometry.

    Parameters
    ----------
    file : str or Path
        The URDF file.
    root, tip : str
        The arm's base and flange frames, as for
        :func:`~dualarm_qp.kinematics.urdf_arm`.
    package_dirs : sequence of str or Path, optional
        Folders in which ``package://<name>/...`` mesh paths are looked up (a folder
        holding ``<name>``). Default: every folder above the URDF file.

    Returns
    -------
    dict of int to Capsule
        Key ``i`` in 1..n: the capsule containing the collision geometry of every link
        joint ``i`` moves (below it, up to the next joint of the arm, locked joints such
        as a gripper's included), in the frame of joint ``i``. Key 0: the geometry of
        ``root`` and of the links fixed to it (no joint in between), in the base frame
        (``root``). Everything else (another arm, a head, a torso above ``root``) is
        left out. Joints that are not the arm's are at zero, as in
        :func:`~dualarm_qp.kinematics.urdf_arm`.

    Raises
    ------
    RobotModelError
        Unreadable URDF, a mesh that cannot be found, or a chain ``urdf_arm`` rejects.
    InvalidInputError
        A collision geometry that cannot be bounded (see
        :func:`~dualarm_qp.geometry.fit.geometry_balls`).

    Notes
    -----
    The fit takes about a second for a 7-joint arm. Its result is kept on disk, keyed by
    the collision geometry read (:mod:`~dualarm_qp.geometry.capsule_cache`: every
    process that builds the same arm reads it there), and for the life of the process,
    keyed by the file's path, size and modification time, the chain and the package
    folders (a sweep or a bench builds the same arms many times; this also skips
    reading the meshes). Capsules are immutable, so the copies share them.
    """
    path = Path(file).resolve()
    try:
        st = path.stat()
    except OSError:
        return _urdf_capsules(file, root, tip, package_dirs=package_dirs)
    dirs = None if package_dirs is None else tuple(str(p) for p in package_dirs)
    key = (str(path), st.st_size, st.st_mtime_ns, root, tip, dirs)
    cached = _FITTED.get(key)
    if cached is None:
        cached = _urdf_capsules(file, root, tip, package_dirs=package_dirs)
        if len(_FITTED) >= _FITTED_MAX:
            _FITTED.pop(next(iter(_FITTED)))
        _FITTED[key] = cached
    return dict(cached)


#: Capsules already fitted in this process (:func:`urdf_capsules`), at most
#: ``_FITTED_MAX`` chains.
_FITTED: dict[tuple[Any, ...], dict[int, Capsule]] = {}
_FITTED_MAX = 32


def _urdf_capsules(file: str | Path, root: str, tip: str, *,
                   package_dirs: Any = None) -> dict[int, Capsule]:
    """Fit the capsules of :func:`urdf_capsules`, or read them from the capsule cache."""
    balls: dict[int, list[tuple[Any, Any]]] = {}
    for key, obj, pose in chain_collision_objects(file, root, tip, package_dirs=package_dirs):
        balls.setdefault(key, []).append(geometry_balls(obj.geometry, pose.homogeneous))
    return cached_fit(balls)


def chain_collision_objects(file: str | Path, root: str, tip: str, *,
                            package_dirs: Any = None) -> list[tuple[int, Any, pin.SE3]]:
    """Return the URDF's collision objects on the arm ``urdf_arm(file, root, tip)``, placed.

    Returns
    -------
    list of (int, pinocchio.GeometryObject, pinocchio.SE3)
        For every collision object on the chain, in the URDF's order: its key (as in
        :func:`urdf_capsules`: ``i`` in 1..n for the links joint ``i`` moves, 0 for the
        root and the links fixed to it), the object (its ``geometry`` is coal's, the
        mesh ``scale`` applied) and its pose in frame ``key`` (joint ``i``, or ``root``)
        [m]. Objects off the chain (another arm, a head) are left out.

    Raises
    ------
    RobotModelError
        Unreadable URDF, a mesh that cannot be found, or a chain ``urdf_arm`` rejects.
    """
    path = Path(file)
    arm = urdf_arm(path, root, tip)  # checks the file, the frames and the chain
    model = pin.buildModelFromUrdf(str(path))
    dirs = ([str(p) for p in path.resolve().parents] if package_dirs is None
            else [str(p) for p in package_dirs])
    try:
        geom = pin.buildGeomFromUrdf(model, str(path), pin.GeometryType.COLLISION,
                                     package_dirs=dirs)
    except (RuntimeError, ValueError, OSError) as err:
        raise RobotModelError(f"cannot read the collision geometry of {path}: {err} "
                              f"(package folders searched: {', '.join(dirs)})",
                              "file") from None
    chain = [model.getJointId(name) for name in arm.joint_names]
    data = model.createData()
    pin.forwardKinematics(model, data, pin.neutral(model))
    pin.updateFramePlacements(model, data)
    root_id = frame_id(model, root, "root", model.name)
    root_joint = model.frames[root_id].parentJoint
    out = []
    for obj in geom.geometryObjects:
        movers = [j for j in model.supports[obj.parentJoint] if j in chain]
        if not (movers or (obj.parentJoint == root_joint
                           and frame_below(model, obj.parentFrame, root_id))):
            continue  # not on the arm: another arm, a head, a torso
        key = chain.index(movers[-1]) + 1 if movers else 0
        frame = data.oMi[movers[-1]] if movers else data.oMf[root_id]
        # GeometryObject.placement is relative to its parent joint.
        out.append((key, obj, frame.actInv(data.oMi[obj.parentJoint] * obj.placement)))
    return out


def example_robot_capsules(robot: str, root: str, tip: str) -> dict[int, Capsule]:
    """Capsules of ``example_robot_arm(robot, root, tip)`` (see :func:`urdf_capsules`).

    Example: ``example_robot_capsules("ur5", "base_link", "tool0")``.

    Raises
    ------
    RobotModelError
        example-robot-data is not installed, or an unknown robot or chain.
    """
    return urdf_capsules(example_robot_urdf(robot), root, tip)


def dh_capsules(arm: SerialArm, radii: Any = None) -> dict[int, Capsule]:
    """One capsule per segment between consecutive DH frame origins of a DH arm.

    Segment ``i`` (1..n) joins the origins of DH frames ``i-1`` and ``i``. It is rigid in
    the frame of the link that carries it, which depends on the convention: in a
    ``standard`` table the origin of frame ``i-1`` lies on the axis of joint ``i``, so
    segment ``i`` moves with frame ``i`` (key ``i``); in a ``modified`` table the origin
    of frame ``i`` lies on the axis of joint ``i``, so segment ``i`` moves with frame
    ``i-1`` (key ``i-1``, the base frame for segment 1). A segment of zero length gives
    a sphere.

    Parameters
    ----------
    arm : SerialArm
        An arm built from a DH table.
    radii : array_like, shape (n,), optional
        Radius of segment ``i`` at index ``i-1`` [m], positive. Default: for the PUMA
        560 preset (``arm.source == "preset:puma560"``), :data:`PUMA560_LINK_RADII`;
        required otherwise.

    Returns
    -------
    dict of int to Capsule
        Keyed by the index of the frame each capsule is given in (the rows of
        ``arm.link_frames(q)``).

    Raises
    ------
    InvalidInputError
        Not a DH arm, no radii for an arm other than the PUMA preset, or radii that
        are not n finite positive numbers.
    """
    dh = arm.dh
    if dh is None:
        raise InvalidInputError(f"{arm.name}: dh_capsules needs an arm built from a DH "
                                f"table (this one is {arm.source}); see urdf_capsules")
    if radii is None:
        if arm.source != "preset:puma560":
            raise InvalidInputError(f"{arm.name}: give the capsule radii [m], one per "
                                    "link (defaults exist for the PUMA 560 preset only)")
        radii = PUMA560_LINK_RADII
    r = as_array(radii, "radii", (dh.n,))
    out: dict[int, Capsule] = {}
    for i in range(dh.n):
        a, alpha, d = float(dh.a[i]), float(dh.alpha[i]), float(dh.d[i])
        if dh.convention == "standard":  # origin of frame i in frame i+1 (rows from 0)
            out[i + 1] = Capsule(np.array([-a, -d * np.sin(alpha), -d * np.cos(alpha)]),
                                 np.zeros(3), r[i])
        else:  # origin of frame i+1 in frame i
            out[i] = Capsule(np.zeros(3), np.array([a, -d * np.sin(alpha), d * np.cos(alpha)]),
                             r[i])
    return out


def arm_urdf_chain(arm: SerialArm) -> tuple[Path, str, str] | None:
    """Return the robot file and chain ``(file, root, tip)`` recorded in ``arm.source``.

    None for an arm without one (a DH table or a bare Pinocchio model).
    """
    kind, _, rest = arm.source.partition(":")
    where, _, chain = rest.rpartition(" ")
    root, _, tip = chain.partition("->")
    if kind not in ("urdf", "example_robot") or not (where and root and tip):
        return None
    return (example_robot_urdf(where) if kind == "example_robot" else Path(where)), root, tip


def arm_capsules(arm: SerialArm, *, radii: Any = None,
                 package_dirs: Any = None) -> dict[int, Capsule]:
    """Return the capsules of an arm, keyed like ``arm.link_frames(q)``, whatever its source.

    A DH arm gets :func:`dh_capsules` (``radii`` as there); an arm built by
    :func:`~dualarm_qp.kinematics.urdf_arm` or
    :func:`~dualarm_qp.kinematics.example_robot_arm` gets :func:`urdf_capsules` of the
    file and chain recorded in ``arm.source``.

    Raises
    ------
    InvalidInputError
        An arm built from a bare Pinocchio model (no file to read: use
        :func:`urdf_capsules`), ``radii`` given for a URDF arm, or a file whose chain
        no longer has the arm's joints.
    """
    if arm.dh is not None:
        return dh_capsules(arm, radii)
    recorded = arm_urdf_chain(arm)
    if recorded is None:
        raise InvalidInputError(f"{arm.name}: no robot file recorded for this arm "
                                f"(source {arm.source!r}); use urdf_capsules(file, root, tip)")
    if radii is not None:
        raise InvalidInputError(f"{arm.name}: radii apply to DH arms only; a URDF arm's "
                                "capsules are fitted to its collision geometry")
    file, root, tip = recorded
    found = urdf_arm(file, root, tip).joint_names
    if found != arm.joint_names:
        raise InvalidInputError(f"{arm.name}: the chain {root}->{tip} of {file} has joints "
                                f"{found}, the arm has {arm.joint_names}")
    return urdf_capsules(file, root, tip, package_dirs=package_dirs)
