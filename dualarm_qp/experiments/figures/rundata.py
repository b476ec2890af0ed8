"""What the figures of a run draw: the recorded trajectory and the limits it had.

:class:`RunData` reads ``trajectory.csv`` (SI units, one row per sample); the joint
counts come from its header (``ql1..qlN``, ``qf1..qfN``), so arms of any size, and the
optional ``grasp_leader`` column of a leader whose grasp also slides, are read alike.
:class:`PlotLimits` holds the ranges and speed limits, taken from the
:class:`~dualarm_qp.experiments.setup.Experiment` (a run folder does not record them).
"""

from __future__ import annotations

import csv
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from ...errors import DualArmError, InvalidInputError

if TYPE_CHECKING:
    from ..setup import Experiment

FloatArray = NDArray[np.float64]

#: Columns holding text, not numbers.
TEXT_COLUMNS = ("status", "leader_status", "clearance_pair")


@dataclass(frozen=True)
class RunData:
    """The columns of one run's ``trajectory.csv``.

    Attributes
    ----------
    columns : dict of str to ndarray
        Every column by its header name: floats (SI units), or strings for
        :data:`TEXT_COLUMNS`.
    """

    columns: dict[str, NDArray[Any]]

    @classmethod
    def read(cls, path: str | Path) -> RunData:
        """Read a ``trajectory.csv`` written by :func:`~..outputs.write_trace_csv`.

        Raises
        ------
        InvalidInputError
            The file has no header, no ``t`` column, or a row of the wrong length.
        """
        path = Path(path)
        with path.open(newline="") as fh:
            rows = list(csv.reader(fh))
        if not rows or "t" not in rows[0]:
            raise InvalidInputError(f"{path} is not a trajectory.csv (no header with a "
                                    "'t' column)")
        header, body = rows[0], rows[1:]
        for k, row in enumerate(body):
            if len(row) != len(header):
                raise InvalidInputError(f"{path}: row {k + 2} has {len(row)} cells, the "
                                        f"header {len(header)}")
        cols: dict[str, NDArray[Any]] = {}
        for j, name in enumerate(header):
            cells = [row[j] for row in body]
            if name in TEXT_COLUMNS:
                cols[name] = np.array(cells, dtype=str)
            else:
                cols[name] = np.array([float(c) if c else np.nan for c in cells], dtype=float)
        return cls(cols)

    @classmethod
    def from_columns(cls, columns: dict[str, Any]) -> RunData:
        """Return what :meth:`read` reads from the file these ``columns`` are written to.

        ``columns``: those of :func:`~..outputs.csv_columns`. The file holds each number's
        ``repr``, which gives it back exactly: the same values, without writing the file
        and reading it again.
        """
        cols: dict[str, NDArray[Any]] = {}
        for name, values in columns.items():
            if name in TEXT_COLUMNS:
                cols[name] = np.array([str(v) for v in values], dtype=str)
                continue
            array = np.asarray(values)
            if array.dtype.kind not in "biuf":  # an empty cell among the numbers: NaN, as read
                array = np.array([np.nan if v is None or v == "" else float(v)
                                  for v in values])
            cols[name] = array.astype(float)
        if "t" not in cols:
            raise InvalidInputError("a run's columns without a 't' column")
        return cls(cols)

    def __len__(self) -> int:
        return int(self.columns["t"].shape[0])

    def has(self, name: str) -> bool:
        """Whether the column ``name`` was recorded."""
        return name in self.columns

    def col(self, name: str) -> FloatArray:
        """Return the numeric column ``name`` (NaN everywhere when it was not recorded)."""
        if name not in self.columns:
            return np.full(len(self), np.nan)
        return np.asarray(self.columns[name], dtype=float)

    def _numbered(self, prefix: str) -> list[str]:
        pat = re.compile(rf"{re.escape(prefix)}(\d+)")
        found = [(int(m.group(1)), n) for n in self.columns if (m := pat.fullmatch(n))]
        return [n for _, n in sorted(found)]

    def n_joints(self, arm: str) -> int:
        """Joint count of ``arm`` (``"l"`` leader, ``"f"`` follower), from the header."""
        return len(self._numbered(f"q{arm}"))

    def joints(self, arm: str) -> FloatArray:
        """Return the recorded (realised) joints of ``arm`` [rad], shape (samples, n)."""
        return self._stack(self._numbered(f"q{arm}"))

    def commanded_rates(self, arm: str) -> FloatArray:
        """Commanded joint rates of ``arm`` [rad/s] (row k: applied over the next sample)."""
        return self._stack(self._numbered(f"q{arm}_dot"))

    def realised_rates(self, arm: str) -> FloatArray:
        """Realised joint rates of ``arm`` [rad/s]: finite differences of the joints.

        Row k is ``(q[k+1] - q[k]) / (t[k+1] - t[k])``, the rate over the sample the
        command of row k was applied; the last row is NaN.
        """
        return realised_rate(self.col("t"), self.joints(arm))

    def realised_accelerations(self, arm: str) -> FloatArray:
        """Realised joint accelerations of ``arm`` [rad/s^2], from the realised rates.

        Row k is ``(v[k] - v[k-1]) / dt`` with ``v[k]`` the realised rate over sample k
        and ``v[-1] = 0`` (the run started at rest); the last row is NaN.
        """
        v = self.realised_rates(arm)
        t = self.col("t")
        dt = np.diff(t, append=np.nan)
        before = np.vstack([np.zeros((1, v.shape[1])), v[:-1]])
        return (v - before) / dt[:, None]

    def realised_jerks(self, arm: str) -> FloatArray:
        """Realised joint jerks of ``arm`` [rad/s^3], from the realised accelerations.

        Row k is ``(a[k] - a[k-1]) / dt`` with ``a[-1] = 0`` (the run started at rest);
        the last row is NaN.
        """
        a = self.realised_accelerations(arm)
        dt = np.diff(self.col("t"), append=np.nan)
        before = np.vstack([np.zeros((1, a.shape[1])), a[:-1]])
        return (a - before) / dt[:, None]

    @property
    def t(self) -> FloatArray:
        """Sample times [s]."""
        return self.col("t")

    def _stack(self, names: list[str]) -> FloatArray:
        if not names:
            return np.zeros((len(self), 0))
        return np.column_stack([self.col(n) for n in names])


def realised_rate(t: Any, values: Any) -> FloatArray:
    """Forward finite differences of ``values`` over ``t``; the last row is NaN.

    Parameters
    ----------
    t : array_like, shape (n,)
        Sample times [s].
    values : array_like, shape (n,) or (n, k)
        Recorded values (SI units).

    Returns
    -------
    ndarray, same shape as ``values``
        Rates in SI units per second.
    """
    t = np.asarray(t, dtype=float)
    v = np.asarray(values, dtype=float)
    out = np.full(v.shape, np.nan)
    if t.size > 1:
        dt = np.diff(t)
        out[:-1] = np.diff(v, axis=0) / (dt[:, None] if v.ndim == 2 else dt)
    return out


@dataclass(frozen=True)
class ArmLimits:
    """Range [rad], speed [rad/s], acceleration [rad/s^2] and jerk [rad/s^3] limits of an arm."""

    q_min: FloatArray
    q_max: FloatArray
    qd_max: FloatArray
    qdd_max: FloatArray | None = None
    qddd_max: FloatArray | None = None


@dataclass(frozen=True)
class DisplayUnits:
    """The units the figures show angles and lengths in: the experiment file's.

    Attributes
    ----------
    angle : {"deg", "rad"}
        Unit of joint angles (and ``<angle>/s`` of joint rates).
    length : {"mm", "m"}
        Unit of the grasp coordinate (and ``<length>/s`` of the sliding speed).
    per_rad : float
        Display units of angle in one radian (set from ``angle``).
    per_m : float
        Display units of length in one metre (set from ``length``).
    """

    angle: str = "deg"
    length: str = "mm"
    per_rad: float = field(init=False, repr=False, compare=False)
    per_m: float = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        # The experiment file's units, read from its schema here only: a process that
        # draws figures it was sent does not import the schema.
        from ..config import ANGLE_SCALE, LENGTH_SCALE

        if self.angle not in ANGLE_SCALE or self.length not in LENGTH_SCALE:
            raise InvalidInputError(f"display units must be an angle in {list(ANGLE_SCALE)} "
                                    f"and a length in {list(LENGTH_SCALE)}, got "
                                    f"{self.angle!r}, {self.length!r}")
        object.__setattr__(self, "per_rad", 1.0 / ANGLE_SCALE[self.angle])
        object.__setattr__(self, "per_m", 1.0 / LENGTH_SCALE[self.length])

    @classmethod
    def of_file(cls, path: str | Path) -> DisplayUnits:
        """Read the ``units`` block of the experiment file at ``path``.

        Degrees and millimetres when there is no readable experiment file (an
        experiment built in code).
        """
        from ..config import load_config

        if not Path(path).is_file():
            return cls()
        try:
            units = load_config(Path(path)).units
        except DualArmError:
            return cls()
        return cls(angle=units.angle, length=units.length)


@dataclass(frozen=True)
class PlotLimits:
    """The limits a run's figures draw, in SI units.

    Attributes
    ----------
    leader, follower : ArmLimits
        Joint ranges [rad] and speed limits [rad/s].
    grasp_range : (float, float)
        Follower grasp range ``(sigma_min, sigma_max)`` [m].
    grasp_speed_max : float
        Sliding speed limit [m/s]; infinite when the run has none.
    speed_limits_enforced : bool
        Whether the run's step kept the speed limits (``velocity_limits``); when it
        did not, the arms' speed limits are drawn as a reference only.
    closure, tracking : (float, float)
        ``(position [m], rotation [rad])`` tolerances of the closure and the leader.
    singular_value_min : float
        Singularity threshold on the smallest singular value (0: none).
    leader_grasp_range : (float, float) or None
        Range [m] of the leader's grasp when it slides too (None: a rigid grasp).
    units : DisplayUnits
        What the figures show angles and lengths in (default degrees and millimetres).
    acceleration_limits_enforced : bool
        Whether the run's step kept the joints' acceleration limits.
    jerk_limits_enforced : bool
        Whether the run's step kept the joints' jerk limits.
    clearance : (float, float) or None
        ``(d_s, d_i)`` [m], the safety and the influence distance, of a task with a
        collision scene (None without one).
    clearance_enforced : bool
        Whether the run's step kept the clearance (collision avoidance enabled; else it
        was only measured).
    """

    leader: ArmLimits
    follower: ArmLimits
    grasp_range: tuple[float, float]
    grasp_speed_max: float
    speed_limits_enforced: bool
    closure: tuple[float, float]
    tracking: tuple[float, float]
    singular_value_min: float
    leader_grasp_range: tuple[float, float] | None = None
    units: DisplayUnits = field(default_factory=DisplayUnits)
    acceleration_limits_enforced: bool = False
    clearance: tuple[float, float] | None = None
    clearance_enforced: bool = False
    jerk_limits_enforced: bool = False

    @classmethod
    def from_experiment(cls, exp: Experiment) -> PlotLimits:
        """Read the limits from the experiment a run was made with, and its file's units."""
        task = exp.task

        def arm(a: Any) -> ArmLimits:
            return ArmLimits(np.asarray(a.q_min, dtype=float), np.asarray(a.q_max, dtype=float),
                             np.asarray(a.qd_max, dtype=float),
                             np.asarray(getattr(a, "qdd_max", np.full(a.n, np.inf)),
                                        dtype=float),
                             np.asarray(getattr(a, "qddd_max", np.full(a.n, np.inf)),
                                        dtype=float))

        opts = exp.options
        speed = float(opts.grasp_speed_max) if opts.velocity_limits else float("inf")
        leader_surface = getattr(task, "leader_surface", None)  # a sliding leader grasp
        leader_range = None if leader_surface is None else (
            float(leader_surface.sigma_min), float(leader_surface.sigma_max))
        scene = getattr(task, "scene", None)
        collision = None if scene is None else scene.settings
        return cls(leader=arm(task.leader), follower=arm(task.follower),
                   grasp_range=(float(task.surface.sigma_min), float(task.surface.sigma_max)),
                   grasp_speed_max=speed, speed_limits_enforced=bool(opts.velocity_limits),
                   closure=(float(exp.limits.closure[0]), float(exp.limits.closure[1])),
                   tracking=(float(exp.limits.tracking[0]), float(exp.limits.tracking[1])),
                   singular_value_min=float(exp.limits.singular_value_min),
                   leader_grasp_range=leader_range, units=DisplayUnits.of_file(exp.path),
                   acceleration_limits_enforced=bool(getattr(opts, "acceleration_limits",
                                                             False)),
                   clearance=None if collision is None else (
                       float(collision.safety_distance), float(collision.influence_distance)),
                   clearance_enforced=collision is not None and bool(collision.enabled),
                   jerk_limits_enforced=bool(getattr(opts, "jerk_limits", False)))

    def arm(self, arm: str) -> ArmLimits:
        """Limits of ``"l"`` (leader) or ``"f"`` (follower)."""
        return self.leader if arm == "l" else self.follower


def run_title(exp: Experiment) -> str:
    """Return the figures' title prefix of a run: ``"<experiment> (<solver>)"``."""
    return f"{exp.name} ({exp.solver_name})"
