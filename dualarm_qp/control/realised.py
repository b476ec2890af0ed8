"""The realised motion of a run, measured against every limit.

A limit is kept when the recorded motion keeps it, not when the commanded step did.
Speeds are the finite differences of consecutive recorded positions over ``dt``;
accelerations the finite differences of those speeds over ``dt`` (the first one from the
rates the run started with, zero from rest); ranges are read from the recorded
positions. Three rules:

* **speed**: ``|q[k+1] - q[k]| / dt <= v_max (1 + SPEED_RTOL)`` for every sample;
* **acceleration** (when the run keeps acceleration limits):
  ``|v[k] - v[k-1]| / dt <= a_max (1 + ACCEL_RTOL)``, with ``v[-1]`` the initial rates;
* **jerk** (when the run keeps jerk limits): ``|a[k] - a[k-1]| / dt <= j_max (1 +
  JERK_RTOL)``, ``a`` the accelerations above (third differences of the positions),
  with ``a[-1] = 0`` (the run starts at rest or at constant rates);
* with the samples' own times (a cell's clock, which can tick late), each difference
  divides by its own interval instead of ``dt`` (:func:`_intervals`);
* **range**: the distance outside ``[lo, hi]`` never exceeds its smallest earlier value
  by more than ``RANGE_TOL``: a variable that starts outside its range never moves
  further out, and one that is inside (or got back inside) never leaves it (compared
  with the best so far, so a slow creep cannot pass in steps under the tolerance).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

#: Relative slack on a speed limit for finite-difference rounding.
SPEED_RTOL = 1e-6

#: Relative slack on an acceleration limit for finite-difference rounding.
ACCEL_RTOL = 1e-6

#: Relative slack on a jerk limit for finite-difference rounding (a third difference
#: loses about three digits more than a first one).
JERK_RTOL = 1e-5

#: Absolute slack [rad or m] on a range: the solvers' bound tolerance (1e-7 per s) over
#: one sample, plus rounding.
RANGE_TOL = 1e-9


@dataclass(frozen=True)
class Breach:
    """The first sample at which a realised limit was broken.

    Attributes
    ----------
    criterion : {"range", "speed", "acceleration", "jerk"}
        Which rule was broken.
    variable : str
        Name of the variable (``"ql2"``, ``"qf3"``, ``"grasp"``).
    sample : int
        Row of the trace (for a speed: the first row of the pair).
    amount : float
        The realised value: distance outside the range [rad or m], speed [rad/s or
        m/s], acceleration [rad/s^2 or m/s^2] or jerk [rad/s^3 or m/s^3].
    limit : float
        What it was allowed: the smallest earlier distance outside the range, the
        speed limit or the acceleration limit.
    """

    criterion: str
    variable: str
    sample: int
    amount: float
    limit: float

    def describe(self, dt: float) -> str:
        """One line for a person."""
        if self.criterion == "jerk":
            return (f"{self.variable} changed its acceleration at {self.amount:.6g} per s^3 "
                    f"at sample {self.sample} (limit {self.limit:.6g}, "
                    f"{self.amount / self.limit:.3g}x)")
        if self.criterion == "acceleration":
            return (f"{self.variable} accelerated at {self.amount:.6g} per s^2 at sample "
                    f"{self.sample} (limit {self.limit:.6g}, "
                    f"{self.amount / self.limit:.3g}x)")
        if self.criterion == "speed":
            return (f"{self.variable} moved at {self.amount:.6g} per s between samples "
                    f"{self.sample} and {self.sample + 1} (limit {self.limit:.6g}, "
                    f"{self.amount / self.limit:.3g}x)")
        if self.limit > 0:
            return (f"{self.variable} moved further outside its range at sample "
                    f"{self.sample}: {self.amount:.6g} outside, was {self.limit:.6g}")
        return (f"{self.variable} left its range at sample {self.sample} "
                f"(t = {self.sample * dt:.4f} s after the start): {self.amount:.6g} outside")


@dataclass(frozen=True)
class LimitReport:
    """Worst realised use of the limits of one group of variables (an arm, the grasp).

    Attributes
    ----------
    range_ratio : float
        ``max |x - mid| / half_width`` over samples and variables: at most 1 inside the
        ranges, above 1 outside (0 when no range is finite).
    range_ratio_start : float
        The same at the first sample: a run that starts outside a range (the paper's
        Table 2 does) shows it here; the rule only forbids moving further out.
    speed_ratio : float
        ``max |dx/dt| / v_max`` (NaN when no speed limit is finite: nothing to compare;
        0 for a single sample: nothing moved).
    range_excess : float
        Largest distance outside a range [rad or m] (0 when always inside).
    worst_range, worst_speed : str
        The variables that reached ``range_ratio`` and ``speed_ratio``.
    breach : Breach or None
        The first broken rule, if any.
    acceleration_ratio : float
        ``max |dv/dt| / a_max`` (NaN when no acceleration limit is finite).
    worst_acceleration : str
        The variable that reached it.
    jerk_ratio : float
        ``max |da/dt| / j_max`` (NaN when no jerk limit is finite).
    worst_jerk : str
        The variable that reached it.
    """

    range_ratio: float
    range_ratio_start: float
    speed_ratio: float
    range_excess: float
    worst_range: str
    worst_speed: str
    breach: Breach | None
    acceleration_ratio: float = math.nan
    worst_acceleration: str = ""
    jerk_ratio: float = math.nan
    worst_jerk: str = ""

    def as_dict(self) -> dict[str, object]:
        """JSON-ready."""
        return {"range_ratio_max": self.range_ratio,
                "range_ratio_start": self.range_ratio_start,
                "speed_ratio_max": self.speed_ratio,
                "range_excess_max": self.range_excess, "worst_range": self.worst_range,
                "worst_speed": self.worst_speed,
                "acceleration_ratio_max": self.acceleration_ratio,
                "worst_acceleration": self.worst_acceleration,
                "jerk_ratio_max": self.jerk_ratio, "worst_jerk": self.worst_jerk}


def _intervals(dt: float | FloatArray, rows: int) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Return the intervals [s] the differences of :func:`measure` divide by.

    ``dt`` is the sampling interval, or the samples' times (one per row). Speeds ``v[k]``
    (between samples ``k`` and ``k + 1``) divide by ``t[k + 1] - t[k]``; accelerations
    (between ``v[k - 1]`` and ``v[k]``) by the distance of their midpoints; jerks (between
    the accelerations at ``t[k - 1]`` and ``t[k]``) by ``t[k] - t[k - 1]``. Before the
    first sample, the times repeat the first interval. Equal intervals give ``dt`` for all.
    """
    n = max(rows - 1, 0)
    if np.ndim(dt) == 0:
        h = np.full(n, float(dt))
        return h, h, h
    t = np.asarray(dt, dtype=np.float64)
    h = np.diff(t)
    if n == 0:
        return h, h, h
    mid = np.r_[h[0], 0.5 * (t[2:] - t[:-2])]
    back = np.r_[h[0], h[:-1]]
    return h, mid, back


def measure(x: FloatArray, lo: FloatArray, hi: FloatArray, v_max: FloatArray,
            dt: float | FloatArray,
            names: Sequence[str], *, speed_rule: bool = True,
            a_max: FloatArray | None = None, v_start: FloatArray | None = None,
            acceleration_rule: bool = False, j_max: FloatArray | None = None,
            jerk_rule: bool = False) -> LimitReport:
    """Measure the realised motion ``x`` (rows: samples) against its limits.

    Parameters
    ----------
    x : ndarray, shape (rows, n)
        Recorded positions [rad or m].
    lo, hi : ndarray, shape (n,)
        Ranges (may be infinite).
    v_max : ndarray, shape (n,)
        Speed limits [per s] (may be infinite).
    dt : float or ndarray, shape (rows,)
        Sampling interval [s], or each sample's time [s] (a cell's clock: the
        differences divide by the intervals between those, :func:`_intervals`).
    names : sequence of str
        Variable names for the report.
    speed_rule : bool
        Whether a speed above ``v_max`` is a breach (False: the speed ratio is only
        reported, for a run whose step did not impose the speed limits).
    a_max : ndarray, shape (n,), optional
        Acceleration limits [per s^2] (may be infinite; None: not measured).
    v_start : ndarray, shape (n,), optional
        The rates the run started with [per s] (default zero: from rest).
    acceleration_rule : bool
        Whether an acceleration above ``a_max`` is a breach.
    j_max : ndarray, shape (n,), optional
        Jerk limits [per s^3] (may be infinite; None: not measured).
    jerk_rule : bool
        Whether a jerk above ``j_max`` is a breach.
    """
    x = np.asarray(x, dtype=np.float64)
    x = x.reshape(x.shape[0], -1) if x.ndim != 2 else x
    lo, hi, v_max = (np.broadcast_to(np.asarray(a, dtype=np.float64), x.shape[1:])
                     for a in (lo, hi, v_max))
    rows = x.shape[0]
    if rows == 0:
        return LimitReport(0.0, 0.0, math.nan, 0.0, "", "", None)
    ratio, excess = _range_use(x, lo, hi)
    jr = int(np.argmax(ratio.max(axis=0)))
    first: list[tuple[int, str, int]] = []  # (sample, rule, variable) of each breach
    h, h_mid, h_back = _intervals(dt, rows)
    speed_ratio, js, speed = _speed_use(x, v_max, h, first if speed_rule else None)
    v0 = np.zeros(x.shape[1]) if v_start is None else np.asarray(v_start, dtype=np.float64)
    jerk_ratio, jj, jerk = _jerks(x, v0, (h, h_mid, h_back), j_max, jerk_rule, first)
    accel_ratio, ja, accel = math.nan, 0, np.zeros((0, x.shape[1]))
    if a_max is not None:
        accel_ratio, ja, accel = _acceleration_use(x, a_max, (h, h_mid), v0,
                                                   first if acceleration_rule else None)
    best = np.minimum.accumulate(excess, axis=0)
    grew = np.argwhere(excess[1:] > best[:-1] + RANGE_TOL)
    first += [(int(k) + 1, "range", int(j)) for k, j in grew[:1]]
    breach: Breach | None = None
    if first:
        k, what, j = min(first)
        if what == "speed":
            breach = Breach("speed", names[j], k, float(speed[k, j]), float(v_max[j]))
        elif what == "jerk":
            breach = Breach("jerk", names[j], k, float(jerk[k, j]),
                            float(np.broadcast_to(np.asarray(j_max), x.shape[1:])[j]))
        elif what == "acceleration":
            breach = Breach("acceleration", names[j], k, float(accel[k, j]),
                            float(np.broadcast_to(np.asarray(a_max), x.shape[1:])[j]))
        else:
            breach = Breach("range", names[j], k, float(excess[k, j]), float(best[k - 1, j]))
    return LimitReport(float(ratio[:, jr].max()), float(ratio[0].max()), speed_ratio,
                       float(excess.max()), names[jr], names[js] if rows > 1 else "none moved",
                       breach, accel_ratio,
                       names[ja] if rows > 1 and accel_ratio == accel_ratio else "",
                       jerk_ratio, names[jj] if rows > 1 and jerk_ratio == jerk_ratio else "")


def _jerks(x: FloatArray, v0: FloatArray, steps: tuple[FloatArray, FloatArray, FloatArray],
           j_max: FloatArray | None, rule: bool,
           first: list[tuple[int, str, int]]) -> tuple[float, int, FloatArray]:
    """Third differences of ``x`` (over ``steps``, :func:`_intervals`) against ``j_max``.

    Returns (ratio, worst, jerks).

    Row ``k`` of the jerks is the change between the accelerations ``a[k-1]`` and
    ``a[k]`` of :func:`measure` (``a[-1] = 0``); a breach is appended to ``first``.
    """
    empty = np.zeros((0, x.shape[1]))
    if j_max is None:
        return math.nan, 0, empty
    j_lim = np.broadcast_to(np.asarray(j_max, dtype=np.float64), x.shape[1:])
    limited = np.isfinite(j_lim)
    if not limited.any():
        return math.nan, 0, empty
    if x.shape[0] < 2:
        return 0.0, 0, empty
    h, h_mid, h_back = steps
    v = np.vstack([v0, np.diff(x, axis=0) / h[:, None]])
    a = np.vstack([np.zeros(x.shape[1]), np.diff(v, axis=0) / h_mid[:, None]])
    jerk = np.abs(np.diff(a, axis=0)) / h_back[:, None]
    jratio = np.where(limited, jerk / np.where(limited, j_lim, 1.0), 0.0)
    jj = int(np.argmax(jratio.max(axis=0)))
    if rule:
        over = np.argwhere(limited & (jerk > j_lim * (1.0 + JERK_RTOL)))
        first += [(int(k), "jerk", int(j)) for k, j in over[:1]]
    return float(jratio[:, jj].max()), jj, jerk

def _range_use(x: FloatArray, lo: FloatArray, hi: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Return each sample's use of each range (``|x - mid| / half``) and its excess outside."""
    finite = np.isfinite(lo) & np.isfinite(hi)
    with np.errstate(invalid="ignore"):  # -inf + inf where a variable has no range
        mid = np.where(finite, 0.5 * (lo + hi), 0.0)
        half = np.where(finite, 0.5 * (hi - lo), 1.0)
    ratio = np.where(finite, np.abs(x - mid) / np.where(half > 0, half, np.inf), 0.0)
    ratio = np.where(finite & (half <= 0) & (x != mid), np.inf, ratio)
    excess = np.maximum(np.maximum(lo - x, x - hi), 0.0)
    return ratio, excess


def _speed_use(x: FloatArray, v_max: FloatArray, h: FloatArray,
               breaches: list[tuple[int, str, int]] | None) -> tuple[float, int, FloatArray]:
    """Return the largest speed ratio, its variable and the speeds [per s].

    ``h`` holds the samples' intervals [s] (:func:`_intervals`).

    The first speed over its limit is appended to ``breaches`` (None: not a breach).
    """
    speed_ratio = 0.0 if np.isfinite(v_max).any() else math.nan  # one sample: no motion
    js = 0
    speed = np.zeros((0, x.shape[1]))
    if x.shape[0] > 1 and np.isfinite(v_max).any():
        speed = np.abs(np.diff(x, axis=0)) / h[:, None]
        limited = np.isfinite(v_max)
        sratio = np.where(limited, speed / np.where(limited, v_max, 1.0), 0.0)
        js = int(np.argmax(sratio.max(axis=0)))
        speed_ratio = float(sratio[:, js].max())
        if breaches is not None:
            over = np.argwhere(limited & (speed > v_max * (1.0 + SPEED_RTOL)))
            breaches += [(int(k), "speed", int(j)) for k, j in over[:1]]
    return speed_ratio, js, speed


def _acceleration_use(x: FloatArray, a_max: FloatArray,
                      steps: tuple[FloatArray, FloatArray], v0: FloatArray,
                      breaches: list[tuple[int, str, int]] | None
                      ) -> tuple[float, int, FloatArray]:
    """Return the largest acceleration ratio, its variable and the accelerations [per s^2].

    ``steps`` holds the samples' intervals and their midpoints' distances [s]
    (:func:`_intervals`), ``v0`` the rates the run started with. The first acceleration
    over its limit is appended to ``breaches`` (None: not a breach); the ratio is NaN
    when no limit is finite.
    """
    accel_ratio, ja, accel = math.nan, 0, np.zeros((0, x.shape[1]))
    a_lim = np.broadcast_to(np.asarray(a_max, dtype=np.float64), x.shape[1:])
    limited = np.isfinite(a_lim)
    if limited.any():
        accel_ratio = 0.0
        if x.shape[0] > 1:
            h, h_mid = steps
            v = np.vstack([v0, np.diff(x, axis=0) / h[:, None]])
            accel = np.abs(np.diff(v, axis=0)) / h_mid[:, None]  # between v[k-1] and v[k]
            aratio = np.where(limited, accel / np.where(limited, a_lim, 1.0), 0.0)
            ja = int(np.argmax(aratio.max(axis=0)))
            accel_ratio = float(aratio[:, ja].max())
            if breaches is not None:
                over = np.argwhere(limited & (accel > a_lim * (1.0 + ACCEL_RTOL)))
                breaches += [(int(k), "acceleration", int(j)) for k, j in over[:1]]
    return accel_ratio, ja, accel



__all__ = ["ACCEL_RTOL", "JERK_RTOL", "RANGE_TOL", "SPEED_RTOL", "Breach", "LimitReport", "measure"]
