"""Serial arms described by Denavit-Hartenberg tables.

Two conventions are supported, both for revolute joints:

``standard`` (Denavit-Hartenberg; Fu, Gonzalez and Lee)
    ``A_i = Rot_z(theta_i) Trans_z(d_i) Trans_x(a_i) Rot_x(alpha_i)``; joint i turns
    about the z axis of frame i-1.
``modified`` (Craig)
    ``A_i = Rot_x(alpha_{i-1}) Trans_x(a_{i-1}) Rot_z(theta_i) Trans_z(d_i)``; joint i
    turns about the z axis of frame i. Row i of the table holds
    ``(a_{i-1}, alpha_{i-1}, d_i, offset_i)``.

with ``theta_i = q_i + offset_i``. The pose of the tool in the world is
``T_world_tool = base @ A_1 ... A_n @ tool``.

Implementation note: both conventions are the same alternating chain of two screw
motions, ``Z(theta, d) = Rot_z(theta) Trans_z(d)`` and ``X(a, alpha) = Trans_x(a)
Rot_x(alpha)``: standard DH is ``Z_1 X_1 Z_2 X_2 ...`` and modified DH is
``X_0 Z_1 X_1 Z_2 ...``. :class:`SerialArm` stores that chain once as a list of steps and
walks it with scalar (Python float) arithmetic, which for a 6-joint arm is several
times faster than numpy on 4x4 matrices; numpy arrays are built only for the outputs.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Literal, NamedTuple

import numpy as np
from numpy.typing import NDArray

from .._validate import as_array, as_pose, check_limits
from ..errors import InvalidInputError, LimitsError, NonFiniteError, ShapeError

FloatArray = NDArray[np.float64]
Convention = Literal["standard", "modified"]

#: A frame as 12 floats: its x, y and z axes and its origin, in world coordinates.
Frame = tuple[float, float, float, float, float, float, float, float, float,
              float, float, float]
#: A joint axis as 6 floats: its unit direction z and a point o on it (world, [m]).
Axis = tuple[float, float, float, float, float, float]


@dataclass(frozen=True)
class DHTable:
    """Denavit-Hartenberg parameters, one row per joint (all revolute).

    Parameters
    ----------
    a : ndarray, shape (n,)
        Link lengths [m] (``a_i`` standard, ``a_{i-1}`` modified).
    alpha : ndarray, shape (n,)
        Link twists [rad] (``alpha_i`` standard, ``alpha_{i-1}`` modified).
    d : ndarray, shape (n,)
        Link offsets along z [m].
    offset : ndarray, shape (n,)
        Joint angle offsets [rad]: ``theta_i = q_i + offset_i``.
    convention : {"standard", "modified"}
        Which DH convention the rows follow.
    """

    a: FloatArray
    alpha: FloatArray
    d: FloatArray
    offset: FloatArray
    convention: Convention = "standard"

    def __post_init__(self) -> None:
        a = as_array(self.a, "a", (-1,))
        n = a.shape[0]
        if n == 0:
            raise InvalidInputError("a DH table needs at least one joint")
        for name in ("a", "alpha", "d", "offset"):
            # Own read-only copies: SerialArm caches these values.
            arr = as_array(getattr(self, name), name, (n,)).copy()
            arr.flags.writeable = False
            object.__setattr__(self, name, arr)
        if self.convention not in ("standard", "modified"):
            raise InvalidInputError(
                f"convention must be 'standard' or 'modified', got {self.convention!r}"
            )

    @classmethod
    def from_rows(cls, rows: Any, convention: Convention = "standard") -> DHTable:
        """Build from an (n, 3) or (n, 4) array of rows ``(a, alpha, d[, offset])``.

        Units: [m, rad, m, rad].

        Raises
        ------
        ShapeError, NonFiniteError, InvalidInputError
            Rows that are not an (n, 3) or (n, 4) array of finite numbers.
        """
        arr = as_array(rows, "DH rows", (-1, -1))  # numeric, finite, two-dimensional
        if arr.shape[1] not in (3, 4):
            raise ShapeError("DH rows", (-1, 4), tuple(arr.shape))
        offset = arr[:, 3] if arr.shape[1] == 4 else np.zeros(arr.shape[0])
        return cls(arr[:, 0], arr[:, 1], arr[:, 2], offset, convention)

    @property
    def n(self) -> int:
        """Number of joints."""
        return int(self.a.shape[0])


class SerialArm:
    """A revolute serial arm: DH kinematics, joint limits, base and tool poses.

    Parameters
    ----------
    dh : DHTable
        Kinematic parameters.
    q_min, q_max : array_like, shape (n,)
        Joint position limits [rad]. Default: no limit (-inf, inf).
    qd_max : array_like, shape (n,)
        Joint speed limits [rad/s], symmetric: ``|qd_i| <= qd_max_i``. Default: inf.
    base : array_like, shape (4, 4)
        ``T_world_base``, the pose of the arm's base frame (frame 0) in the world.
    tool : array_like, shape (4, 4)
        ``T_flange_tool``, the tool frame in the last link frame (frame n).
    name : str
        Label used in messages.

    Raises
    ------
    ShapeError, NonFiniteError, LimitsError, InvalidInputError
        Malformed parameters.
    """

    def __init__(
        self,
        dh: DHTable,
        *,
        q_min: Any = None,
        q_max: Any = None,
        qd_max: Any = None,
        base: Any = None,
        tool: Any = None,
        name: str = "arm",
    ) -> None:
        if not isinstance(dh, DHTable):
            raise InvalidInputError(f"dh must be a DHTable, got {type(dh).__name__}")
        n = dh.n
        self.dh = dh
        self.name = name
        self.q_min = np.full(n, -np.inf) if q_min is None else _limit(q_min, "q_min", n)
        self.q_max = np.full(n, np.inf) if q_max is None else _limit(q_max, "q_max", n)
        check_limits(self.q_min, self.q_max, f"{name} joint limits")
        self.qd_max = np.full(n, np.inf) if qd_max is None else _limit(qd_max, "qd_max", n)
        if (self.qd_max <= 0).any():
            raise LimitsError(f"{name}: qd_max must be positive, got {self.qd_max}")
        self.base = base  # validated by the property setters
        self.tool = tool
        self._steps = _screw_steps(dh)

    # ------------------------------------------------------------------ basics
    @property
    def n(self) -> int:
        """Number of joints."""
        return self.dh.n

    def __repr__(self) -> str:
        return f"SerialArm(name={self.name!r}, n={self.n}, convention={self.dh.convention!r})"

    @property
    def base(self) -> FloatArray:
        """``T_world_base`` (4x4, read-only array; assign a new pose to change it)."""
        return self._base

    @base.setter
    def base(self, value: Any) -> None:
        self._base = _frozen_pose(value, "base")
        self._base_frame = _frame_of(self._base)

    @property
    def tool(self) -> FloatArray:
        """``T_flange_tool`` (4x4, read-only array; assign a new pose to change it)."""
        return self._tool

    @tool.setter
    def tool(self, value: Any) -> None:
        self._tool = _frozen_pose(value, "tool")
        frame = _frame_of(self._tool)
        self._tool_frame = None if frame == _IDENTITY else frame

    def with_base(self, base: Any) -> SerialArm:
        """Return a copy of this arm placed at ``base`` (``T_world_base``)."""
        return SerialArm(self.dh, q_min=self.q_min, q_max=self.q_max, qd_max=self.qd_max,
                         base=base, tool=self.tool, name=self.name)

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
        return as_array(q, name, (self.n,))

    def within_limits(self, q: FloatArray, tol: float = 0.0) -> bool:
        """Whether every joint lies in ``[q_min - tol, q_max + tol]`` [rad]."""
        return bool(np.all(q >= self.q_min - tol) and np.all(q <= self.q_max + tol))

    # --------------------------------------------------------------- kinematics
    def _joint_values(self, q: Any, name: str = "q") -> list[float]:
        """Return validated joint angles as Python floats (cheap path for float arrays)."""
        if isinstance(q, np.ndarray) and q.shape == (self.n,) and q.dtype == np.float64:
            values: list[float] = q.tolist()
            # A NaN or infinity makes the sum non-finite; so can an overflow of huge
            # finite values, which the full check below then lets through.
            if math.isfinite(sum(values)):
                return values
        return self.check_q(q, name).tolist()

    def _chain(self, qs: list[float], *, all_frames: bool = True
               ) -> tuple[list[Frame], list[Axis]]:
        """Walk the kinematic chain at joint angles ``qs`` [rad].

        Returns
        -------
        frames : list of Frame
            World frames 0..n (frame 0 is the base; no tool); only frame n when
            ``all_frames`` is False.
        axes : list of Axis
            For each joint, its axis ``z`` and a point ``o`` on it, as ``(z, o)``
            (the z axis and origin of frame i-1 in standard DH; in modified DH the z
            axis of frame i and the origin of frame i shifted back by ``d_i``).
        """
        x0, x1, x2, y0, y1, y2, z0, z1, z2, p0, p1, p2 = self._base_frame
        frames: list[Frame] = [self._base_frame]
        axes: list[Axis] = []
        cos, sin = math.cos, math.sin
        # Sequential statements with one temporary (no tuple packing) keep this fast.
        for kind, j, u, v, w, record in self._steps:
            if kind == _Z:  # Rot_z(q_j + offset u) Trans_z(d = v)
                axes.append((z0, z1, z2, p0, p1, p2))
                theta = qs[j] + u
                c = cos(theta)
                s = sin(theta)
                t = c * x0 + s * y0
                y0 = c * y0 - s * x0
                x0 = t
                t = c * x1 + s * y1
                y1 = c * y1 - s * x1
                x1 = t
                t = c * x2 + s * y2
                y2 = c * y2 - s * x2
                x2 = t
                if v:
                    p0 += v * z0
                    p1 += v * z1
                    p2 += v * z2
            else:  # Trans_x(a = u) Rot_x(alpha) with v = cos(alpha), w = sin(alpha)
                if u:
                    p0 += u * x0
                    p1 += u * x1
                    p2 += u * x2
                if kind == _X_QUARTER:  # alpha = +-pi/2 exactly: (y, z) <- (w z, -w y)
                    if w > 0.0:
                        y0, z0, y1, z1, y2, z2 = z0, -y0, z1, -y1, z2, -y2
                    else:
                        y0, z0, y1, z1, y2, z2 = -z0, y0, -z1, y1, -z2, y2
                elif kind == _X:
                    t = v * y0 + w * z0
                    z0 = v * z0 - w * y0
                    y0 = t
                    t = v * y1 + w * z1
                    z1 = v * z1 - w * y1
                    y1 = t
                    t = v * y2 + w * z2
                    z2 = v * z2 - w * y2
                    y2 = t
            if record and all_frames:
                frames.append((x0, x1, x2, y0, y1, y2, z0, z1, z2, p0, p1, p2))
        if not all_frames:
            frames = [(x0, x1, x2, y0, y1, y2, z0, z1, z2, p0, p1, p2)]
        return frames, axes

    def _tool_pose(self, flange: Frame) -> Frame:
        """``T_world_tool`` from the world pose of the last link frame."""
        return flange if self._tool_frame is None else _compose(flange, self._tool_frame)

    def link_frames(self, q: Any) -> FloatArray:
        """World poses of frames 0..n (frame 0 is the base), shape (n+1, 4, 4) [m].

        The tool transform is not applied; see :meth:`fk`.
        """
        frames, _ = self._chain(self._joint_values(q))
        return np.array([_matrix_rows(f) for f in frames]).reshape(len(frames), 4, 4)

    def fk(self, q: Any) -> FloatArray:
        """Pose of the tool frame in the world, ``T_world_tool`` (4x4, metres).

        With the default identity tool this is the flange (frame n).
        """
        frames, _ = self._chain(self._joint_values(q), all_frames=False)
        return np.array(_matrix_rows(self._tool_pose(frames[-1]))).reshape(4, 4)

    def jacobian(self, q: Any) -> FloatArray:
        """Geometric Jacobian in the world frame, shape (6, n).

        Rows are ``[v; w]``: the linear velocity [m/s] of the tool frame's origin and
        the angular velocity [rad/s], both in world coordinates, per unit joint rate.
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
        frames, axes = self._chain(self._joint_values(q), all_frames=False)
        tool = self._tool_pose(frames[-1])
        t0, t1, t2 = tool[9], tool[10], tool[11]
        # Column i: [z_i x (p_tool - o_i); z_i] for joint axis z_i through point o_i.
        columns: list[float] = []
        for z0, z1, z2, o0, o1, o2 in axes:
            d0 = t0 - o0
            d1 = t1 - o1
            d2 = t2 - o2
            columns += (z1 * d2 - z2 * d1, z2 * d0 - z0 * d2, z0 * d1 - z1 * d0, z0, z1, z2)
        # One numpy conversion for both outputs: T's 16 entries, then J column by column.
        out = np.array(_matrix_rows(tool) + columns)
        return out[:16].reshape(4, 4), out[16:].reshape(len(axes), 6).T.copy()


_IDENTITY: Frame = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0)


# Kinds of chain step (see the module docstring).
_Z, _X, _X_QUARTER, _X_SHIFT = 0, 1, 2, 3


class _Step(NamedTuple):
    """One screw motion of the chain.

    ``kind == _Z``: ``Rot_z(q[joint] + u) Trans_z(v)`` (``u`` the joint offset [rad],
    ``v`` = d [m]). Otherwise ``Trans_x(u) Rot_x(alpha)`` (``u`` = a [m]) with
    ``v = cos(alpha)``, ``w = sin(alpha)``; ``_X_QUARTER`` marks alpha = +-pi/2 and
    ``_X_SHIFT`` alpha = 0, which skip the multiplications. ``record``: a link frame
    ends after this step.
    """

    kind: int
    joint: int
    u: float
    v: float
    w: float
    record: bool


def _screw_steps(dh: DHTable) -> list[_Step]:
    """Build the chain of :class:`_Step` for a DH table, leaving out identity X steps."""
    steps: list[_Step] = []

    def add_x(a: float, alpha: float, record: bool) -> None:
        if a == 0.0 and alpha == 0.0:
            if record:  # the link frame ends at the previous step instead
                steps[-1] = steps[-1]._replace(record=True)
            return
        kind = _X
        ca, sa = math.cos(alpha), math.sin(alpha)
        if alpha == 0.0:
            kind = _X_SHIFT
        elif abs(abs(alpha) - 0.5 * math.pi) < 1e-15:
            kind, ca, sa = _X_QUARTER, 0.0, math.copysign(1.0, alpha)
        steps.append(_Step(kind, -1, a, ca, sa, record))

    standard = dh.convention == "standard"
    for j in range(dh.n):
        a, alpha = float(dh.a[j]), float(dh.alpha[j])
        if not standard:
            add_x(a, alpha, False)
        steps.append(_Step(_Z, j, float(dh.offset[j]), float(dh.d[j]), 0.0, not standard))
        if standard:
            add_x(a, alpha, True)
    return steps


def _frame_of(T: FloatArray) -> Frame:
    """Convert a 4x4 pose to a 12-float :data:`Frame`."""
    c = T[:3].T.ravel().tolist()  # columns x, y, z, p
    return (c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7], c[8], c[9], c[10], c[11])


def _matrix_rows(f: Frame) -> list[float]:
    """Return the 16 entries, row by row, of the 4x4 pose of a :data:`Frame`."""
    return [f[0], f[3], f[6], f[9], f[1], f[4], f[7], f[10], f[2], f[5], f[8], f[11],
            0.0, 0.0, 0.0, 1.0]


def _compose(f: Frame, g: Frame) -> Frame:
    """Return the frame ``F @ G`` for world frame ``F`` and ``G`` relative to ``F``."""
    x0, x1, x2, y0, y1, y2, z0, z1, z2, p0, p1, p2 = f
    out = []
    for k in range(0, 12, 3):  # each column of G: axis (rotate) or origin (rotate, shift)
        a, b, c = g[k], g[k + 1], g[k + 2]
        out += [a * x0 + b * y0 + c * z0, a * x1 + b * y1 + c * z1, a * x2 + b * y2 + c * z2]
    out[9] += p0
    out[10] += p1
    out[11] += p2
    return (out[0], out[1], out[2], out[3], out[4], out[5], out[6], out[7], out[8],
            out[9], out[10], out[11])


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


def _limit(value: Any, name: str, n: int) -> FloatArray:
    """Limits may be infinite but not NaN; a scalar is broadcast to all joints."""
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as err:
        raise InvalidInputError(f"{name} must be numbers: {err}") from err
    if arr.ndim == 0:
        arr = np.full(n, float(arr))
    if arr.shape != (n,):
        raise ShapeError(name, (n,), arr.shape)
    if np.isnan(arr).any():
        raise NonFiniteError(name)
    return arr
