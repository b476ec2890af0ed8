"""Serial arms: a Pinocchio model with a base placement and a tool frame.

An arm is one chain of revolute joints, one angle each (a continuous joint of a model
becomes a revolute joint with the range +-inf, :mod:`~dualarm_qp.kinematics.continuous`).
Its kinematics (forward kinematics, the
geometric Jacobian, the link frames) are computed by Pinocchio on a model whose
*universe* is the arm's base frame (frame 0): the base placement ``T_world_base`` is
folded into the placements of the joints and frames attached to the universe, and the
tool ``T_flange_tool`` is a frame on the last joint. The model is built in Python; the
computations run in the compiled kernel, on its copy of the model
(:mod:`~dualarm_qp.kinematics.compiled`, Pinocchio's C++ API), one call each.

Where a model comes from does not matter above this module; the builders all return a
:class:`SerialArm`:

* a Denavit-Hartenberg table, ``SerialArm(DHTable(...))`` (:mod:`~dualarm_qp.kinematics.dh`);
* :func:`~dualarm_qp.kinematics.puma560` (the paper's Table 1 PUMA 560, DH);
* one chain of a URDF, :func:`~dualarm_qp.kinematics.urdf_arm`, or of a robot shipped by
  the ``example-robot-data`` package, :func:`~dualarm_qp.kinematics.example_robot_arm`.

The Denavit-Hartenberg table is :mod:`~dualarm_qp.kinematics.dh`; a model from any
other source must be one chain of revolute joints (:mod:`~dualarm_qp.kinematics.chain`).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from .._validate import as_array, as_pose, check_limits, limit_array
from ..errors import InvalidInputError, LimitsError
from .chain import (
    REVOLUTE_JOINTS,
    TOOL_FRAME,
    chain_model,
    check_revolute,
    frame_id,
    model_limits,
    se3,
)
from .compiled import compiled_chain, set_frame_placement, set_joint_placement
from .dh import DHTable, dh_model

FloatArray = NDArray[np.float64]



class SerialArm:
    """A revolute serial arm: a Pinocchio model, joint limits, base and tool poses.

    Parameters
    ----------
    source : DHTable or pinocchio.Model
        A DH table, or a Pinocchio model of one chain of revolute joints (one coordinate
        each, or continuous: made revolute with the range +-inf,
        :func:`~dualarm_qp.kinematics.continuous.one_angle_model`; joint i+1 the child
        of joint i) whose universe is the arm's base frame (see
        :func:`~dualarm_qp.kinematics.urdf_arm` for one chain of a URDF).
    tip : str, optional
        Pinocchio model only: the frame that carries the tool (the flange). Default:
        the frame of the last joint. A DH arm's flange is DH frame n.
    q_min, q_max : array_like, shape (n,)
        Joint position limits [rad]. Default: the model's limits for a Pinocchio model
        (from its URDF; none, -inf and inf, for a continuous joint), no limit (-inf, inf)
        for a DH table.
    qd_max : array_like, shape (n,)
        Joint speed limits [rad/s], symmetric: ``|qd_i| <= qd_max_i``. Default: the
        model's ``velocityLimit`` (a zero there means no limit), inf for a DH table.
    qdd_max : array_like, shape (n,)
        Joint acceleration limits [rad/s^2], symmetric. Default inf (none: a URDF
        states no acceleration limits).
    qddd_max : array_like, shape (n,)
        Joint jerk limits [rad/s^3], symmetric. Default inf (none).
    base : array_like, shape (4, 4)
        ``T_world_base``, the pose of the arm's base frame (frame 0) in the world.
    tool : array_like, shape (4, 4)
        ``T_flange_tool``, the tool frame in the flange frame.
    name : str
        Label used in messages.

    Attributes
    ----------
    source : str
        Where the model came from, for records such as ``summary.json``:
        ``"dh:standard"`` / ``"dh:modified"`` for a DH table and
        ``"pinocchio:<model name>"`` for a model; the builders replace it with their own
        (``"preset:puma560"``, ``"urdf:<file> <root>-><tip>"``,
        ``"example_robot:<robot> <root>-><tip>"``). Copies made by :meth:`with_base`
        and :meth:`with_limits` keep it.

    Raises
    ------
    ShapeError, NonFiniteError, LimitsError, InvalidInputError
        Malformed parameters, or a model that is not one chain of revolute joints.
    """

    def __init__(
        self,
        source: DHTable | Any,
        *,
        tip: str | None = None,
        q_min: Any = None,
        q_max: Any = None,
        qd_max: Any = None,
        qdd_max: Any = None,
        qddd_max: Any = None,
        base: Any = None,
        tool: Any = None,
        name: str = "arm",
    ) -> None:
        self.name = name
        self.dh: DHTable | None
        self.source: str
        if isinstance(source, DHTable):
            if tip is not None:
                raise InvalidInputError("'tip' names a frame of a Pinocchio model; the "
                                        "flange of a DH arm is its last DH frame")
            self.dh = source
            self.source = f"dh:{source.convention}"
            template, links, flange = dh_model(source)
            lo = hi = vel = None
        elif isinstance(source, pin.Model):
            self.dh = None
            self.source = f"pinocchio:{source.name or name}"
            template, links, flange = chain_model(source, tip, name)
            lo, hi, vel = model_limits(template)
        else:
            raise InvalidInputError("an arm is built from a DHTable or a pinocchio.Model, "
                                    f"got {type(source).__name__}")
        n = self._n = int(template.nq)
        if lo is None or hi is None or vel is None:  # a DH table: no limits of its own
            lo, hi, vel = np.full(n, -np.inf), np.full(n, np.inf), np.full(n, np.inf)
        self._set_limits(lo if q_min is None else q_min, hi if q_max is None else q_max,
                         vel if qd_max is None else qd_max,
                         np.full(n, np.inf) if qdd_max is None else qdd_max, n,
                         qddd_max=qddd_max)
        frame = template.frames[flange]
        self._flange = pin.SE3(frame.placement)
        self._tool_id = template.addFrame(pin.Frame(TOOL_FRAME, frame.parentJoint, flange,
                                                    pin.SE3(frame.placement),
                                                    pin.FrameType.OP_FRAME))
        self._links = links
        self._template = template
        self._root_joints = [j for j in range(1, template.njoints) if template.parents[j] == 0]
        self._root_frames = [i for i, f in enumerate(template.frames) if f.parentJoint == 0]
        self._place(base, tool)

    def _set_limits(self, q_min: Any, q_max: Any, qd_max: Any, qdd_max: Any, n: int, *,
                    qddd_max: Any = None) -> None:
        self.q_min = limit_array(q_min, "q_min", n)
        self.q_max = limit_array(q_max, "q_max", n)
        check_limits(self.q_min, self.q_max, f"{self.name} joint limits")
        self.qd_max, self.qdd_max, self.qddd_max = (
            self._rate_limit(v, key, n) for key, v in (
                ("qd_max", qd_max), ("qdd_max", qdd_max),
                ("qddd_max", np.inf if qddd_max is None else qddd_max)))

    def _rate_limit(self, value: Any, key: str, n: int) -> FloatArray:
        limit = limit_array(value, key, n)
        if (limit <= 0).any():
            raise LimitsError(f"{self.name}: {key} must be positive, got {limit}")
        return limit

    def _place(self, base: Any, tool: Any) -> None:
        """Copy the template model, allocate its data, set the limits, base and tool."""
        model = pin.Model(self._template)
        model.lowerPositionLimit = self.q_min
        model.upperPositionLimit = self.q_max
        model.velocityLimit = self.qd_max
        # Pinocchio 4 also keeps a lower velocity limit; leaving it at its default (+max)
        # makes the model invalid for pinocchio.appendModel. The limit is symmetric.
        if hasattr(model, "lowerVelocityLimit"):
            model.lowerVelocityLimit = -self.qd_max
            model.upperVelocityLimit = self.qd_max
        self._model = model
        self._data = model.createData()
        self._tool_frames = (int(self._tool_id),)
        # The kernel's copy of the Pinocchio model (it pickles itself).
        self._chain = compiled_chain(model)
        self.base = base  # validated by the property setters
        self.tool = tool

    # ------------------------------------------------------------------ basics
    @property
    def n(self) -> int:
        """Number of joints."""
        return self._n

    @property
    def model(self) -> Any:
        """The ``pinocchio.Model`` of this arm, base and tool included (do not edit it)."""
        return self._model

    @property
    def data(self) -> Any:
        """A ``pinocchio.Data`` of :attr:`model`, allocated once, for your own calls.

        The arm's methods compute in the compiled kernel (:attr:`chain`) and do not
        write it.
        """
        return self._data

    @property
    def chain(self) -> Any:
        """The kernel's copy of :attr:`model` (``dualarm_qp._kernel.Chain``).

        Every method of the arm computes there. It holds the kinematics of its last update
        (a step's, or the arm's Jacobian methods'); :meth:`fk` and :meth:`link_frames`
        compute in a workspace of their own and leave them (see
        :class:`~dualarm_qp.step.context.ArmKinematics`).
        """
        return self._chain

    @property
    def tool_frame_id(self) -> int:
        """Index of the tool frame in :attr:`model` (an ``OP_FRAME`` on the last joint)."""
        return int(self._tool_id)

    @property
    def joint_names(self) -> list[str]:
        """Names of the joints, base to tip (``joint1`` ... for a DH arm)."""
        return [str(s) for s in list(self._template.names)[1:]]

    @property
    def link_frame_ids(self) -> tuple[int, ...]:
        """Indices in :attr:`model` of the frames of :meth:`link_frames` (0: the base)."""
        return tuple(int(i) for i in self._links)

    @property
    def link_names(self) -> list[str]:
        """Names of the links of :meth:`link_frames`: ``base``, ``link1`` .. ``link<n>``.

        Link ``i`` is the body joint ``i`` moves (``joint_names[i - 1]``), for every arm.
        """
        return ["base", *(f"link{i + 1}" for i in range(len(self._links) - 1))]

    def __repr__(self) -> str:
        if self.dh is not None:
            return (f"SerialArm(name={self.name!r}, n={self.n}, "
                    f"convention={self.dh.convention!r})")
        return f"SerialArm(name={self.name!r}, n={self.n}, model={self._template.name!r})"

    @property
    def base(self) -> FloatArray:
        """``T_world_base`` (4x4, read-only array; assign a new pose to change it)."""
        return self._base

    @base.setter
    def base(self, value: Any) -> None:
        self._base = _frozen_pose(value, "base")
        B = se3(self._base)
        model, chain, template = self._model, self._chain, self._template
        for j in self._root_joints:
            set_joint_placement(model, chain, j, B * template.jointPlacements[j])
        for i in self._root_frames:
            set_frame_placement(model, chain, i, B * template.frames[i].placement)

    @property
    def tool(self) -> FloatArray:
        """``T_flange_tool`` (4x4, read-only array; assign a new pose to change it)."""
        return self._tool

    @tool.setter
    def tool(self, value: Any) -> None:
        self._tool = _frozen_pose(value, "tool")
        set_frame_placement(self._model, self._chain, self._tool_id,
                            self._flange * se3(self._tool))

    def with_base(self, base: Any) -> SerialArm:
        """Return a copy of this arm placed at ``base`` (``T_world_base``)."""
        new = object.__new__(SerialArm)
        new.__dict__.update(self.__dict__)  # shares the (never edited) template model
        new._place(base, self._tool)
        return new

    def with_limits(self, q_min: Any = None, q_max: Any = None,
                    qd_max: Any = None, qdd_max: Any = None, *,
                    qddd_max: Any = None) -> SerialArm:
        """Return a copy of this arm with other limits (None keeps a limit as it is).

        Raises
        ------
        ShapeError, NonFiniteError, LimitsError, InvalidInputError
            Malformed limits.
        """
        new = object.__new__(SerialArm)
        new.__dict__.update(self.__dict__)
        new._set_limits(self.q_min if q_min is None else q_min,
                        self.q_max if q_max is None else q_max,
                        self.qd_max if qd_max is None else qd_max,
                        self.qdd_max if qdd_max is None else qdd_max, self.n,
                        qddd_max=self.qddd_max if qddd_max is None else qddd_max)
        new._place(self._base, self._tool)
        return new

    def set_link_inertias(self, inertias: Any) -> None:
        """Give link ``i`` (the body joint ``i`` moves) its mass, centre and inertia.

        ``inertias[i - 1]`` is a ``pinocchio.Inertia`` in the frame of joint ``i`` of
        :attr:`model` (for a DH arm: DH frame ``i - 1`` turned by ``q_i`` about its z).
        Written into the model (and kept by :meth:`with_base` / :meth:`with_limits`
        copies), where dynamics and statics read it.

        Raises
        ------
        InvalidInputError
            Not one ``pinocchio.Inertia`` per joint.
        """
        items = list(inertias)
        if len(items) != self.n or not all(isinstance(i, pin.Inertia) for i in items):
            raise InvalidInputError(f"{self.name}: give one pinocchio.Inertia per joint "
                                    f"({self.n})")
        for j, inertia in enumerate(items, start=1):
            self._template.inertias[j] = inertia
            self._model.inertias[j] = inertia

    def check_q(self, q: Any, name: str = "q") -> FloatArray:
        """Return ``q`` as a finite (n,) float array or raise a clear error.

        Raises
        ------
        ShapeError
            ``q`` does not have shape (n,).
        NonFiniteError
            ``q`` holds NaN or infinity.
        InvalidInputError
            ``q`` is not numeric.
        """
        if (isinstance(q, np.ndarray) and q.shape == (self.n,) and q.dtype == np.float64
                and math.isfinite(sum(q.tolist()))):
            return q  # the common case, checked cheaply
        # A NaN or infinity makes the sum non-finite; so can an overflow of huge finite
        # values, which the full check then lets through.
        return as_array(q, name, (self.n,))

    def within_limits(self, q: FloatArray, tol: float = 0.0) -> bool:
        """Whether every joint lies in ``[q_min - tol, q_max + tol]`` [rad]."""
        return bool(np.all(q >= self.q_min - tol) and np.all(q <= self.q_max + tol))

    # --------------------------------------------------------------- kinematics
    def link_frames(self, q: Any) -> FloatArray:
        """World poses of frames 0..n (frame 0 is the base), shape (n+1, 4, 4) [m].

        For a DH arm, frame i is DH frame i (frame n the flange); for a Pinocchio model
        it is the frame of joint i (the link it moves), which need not be the flange.
        The tool transform is not applied; see :meth:`fk`.
        """
        links = self._links
        T = np.empty((len(links), 4, 4))
        self._chain.poses(self.check_q(q), links, T.reshape(-1, 4))
        return T

    def fk(self, q: Any) -> FloatArray:
        """Pose of the tool frame in the world, ``T_world_tool`` (4x4, metres).

        With the default identity tool this is the flange.
        """
        T = np.empty((4, 4))
        self._chain.poses(self.check_q(q), self._tool_frames, T)
        return T

    def jacobian(self, q: Any) -> FloatArray:
        """Geometric Jacobian in the world frame, shape (6, n).

        Rows are ``[v; w]``: the linear velocity [m/s] of the tool frame's origin and
        the angular velocity [rad/s], both in world coordinates, per unit joint rate
        (Pinocchio's ``LOCAL_WORLD_ALIGNED`` frame Jacobian of the tool frame).
        """
        return self.fk_jacobian(q)[1]

    def fk_jacobian(self, q: Any) -> tuple[FloatArray, FloatArray]:
        """Tool pose and geometric Jacobian together, sharing one pass (hot path).

        Returns
        -------
        T : ndarray, shape (4, 4)
            ``T_world_tool`` [m].
        J : ndarray, shape (6, n)
            Geometric Jacobian, see :meth:`jacobian`.
        """
        # One kernel call: every joint's Jacobian and every frame's pose are computed,
        # so :attr:`chain` then also serves the link frames (collision rows).
        tool = self._tool_frames
        T = np.empty((4, 4))
        J = np.empty((6, self._n))
        self._chain.compute(self.check_q(q), tool, tool, T, J)
        return T, J


def checked_pose(value: Any, name: str) -> FloatArray:
    """:func:`dualarm_qp._validate.as_pose` with a scalar fast path for float arrays.

    Accepts the same inputs and raises the same errors (it defers to ``as_pose``
    whenever the quick checks do not pass); about 10x cheaper on a valid 4x4 array.
    """
    if isinstance(value, np.ndarray) and value.shape == (4, 4) and value.dtype == np.float64:
        r0, r1, r2, r3 = value.tolist()
        if math.isfinite(sum(r0) + sum(r1) + sum(r2) + sum(r3)) and r3 == [0.0, 0.0, 0.0, 1.0]:
            # Columns of R orthonormal (R^T R = I) and det R = c0 . (c1 x c2) > 0.
            c0 = (r0[0], r1[0], r2[0])
            c1 = (r0[1], r1[1], r2[1])
            c2 = (r0[2], r1[2], r2[2])
            gram = (_dot(c0, c0) - 1.0, _dot(c1, c1) - 1.0, _dot(c2, c2) - 1.0,
                    _dot(c0, c1), _dot(c0, c2), _dot(c1, c2))
            det = (c0[0] * (c1[1] * c2[2] - c1[2] * c2[1])
                   + c0[1] * (c1[2] * c2[0] - c1[0] * c2[2])
                   + c0[2] * (c1[0] * c2[1] - c1[1] * c2[0]))
            if max(map(abs, gram)) <= 1e-6 and det > 0.0:
                return value
    return as_pose(value, name)


def _dot(x: tuple[float, float, float], y: tuple[float, float, float]) -> float:
    return x[0] * y[0] + x[1] * y[1] + x[2] * y[2]


def _frozen_pose(value: Any, name: str) -> FloatArray:
    """Return a validated read-only copy of a pose (identity for None)."""
    T = np.eye(4) if value is None else as_pose(value, name).copy()
    T.flags.writeable = False
    return T


# DHTable, frame_id, check_revolute and REVOLUTE_JOINTS are importable from here too.
__all__ = ["REVOLUTE_JOINTS", "DHTable", "SerialArm", "check_revolute", "checked_pose",
           "frame_id"]
