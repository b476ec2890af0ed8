"""A growing oscillation of the joint servos, found in their velocity error.

A servo whose gains are too stiff for the inertia it drives, at the simulator's time
step, or a closed chain of two stiff servos that excite each other, oscillates about
the commanded motion with an amplitude that grows from one cycle to the next. The
velocity error of its joint (``qd - qd_ref``, sampled at every substep) then changes
sign at a steady rhythm, and the peaks between its sign changes grow.

:func:`growing_oscillation` looks for that in one signal:

1. the signal is cut at its sign changes into half-cycles; each has a peak ``|x|``
   and a duration (a steady offset has no sign change, so no half-cycle);
2. a window of consecutive half-cycles (:data:`WINDOWS`: 8, 16, 32 or 64 cycles, so
   that a slow growth is seen over a longer window) is an oscillation when their
   durations are regular (their standard deviation at most :data:`REGULARITY` of
   their mean, so that noise about zero is not one) and the least-squares line
   through ``ln(peak)`` against time rises by a factor of at least :data:`GROWTH`
   across the window, to a position amplitude (``peak / omega``, ``omega`` the
   window's angular frequency) of at least :data:`FLOOR` at its end;
3. the oscillation started at the smallest peak of the first such window (the trough
   the growth rises from); the window's frequency and the largest peak reached from
   there on are reported with it.

A decaying oscillation (a servo ringing after a change of command) and one of steady
amplitude do not grow; a motion of the plan itself changes the velocity error slowly,
with few sign changes, and is not regular at the servo's rhythm.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

#: Half-cycles in the windows the growth is fitted over (8, 16, 32 and 64 cycles).
WINDOWS = (16, 32, 64, 128)

#: Growth of the fitted amplitude across the window for it to count as growing.
GROWTH = 4.0

#: Smallest position amplitude at the window's end [rad or m] (``peak / omega``):
#: numerical noise about zero can grow by any factor, but never to this.
FLOOR = 1e-4

#: Largest spread of the half-cycles' durations in a window (their standard deviation
#: over their mean): a sine's are all alike, noise about zero gives durations of any
#: length.
REGULARITY = 0.35


@dataclass(frozen=True)
class Oscillation:
    """A growing oscillation found in a signal.

    Attributes
    ----------
    start : int
        Index where the oscillation started: the first value of the half-cycle with the
        smallest peak in the first growing window.
    frequency_hz : float
        Its frequency over that window [Hz].
    growth : float
        The fitted amplitude's growth across that window (>= :data:`GROWTH`).
    cycles : int
        The window's length in cycles.
    peak : float
        The largest ``|x|`` from ``start`` on (the signal's unit, e.g. rad/s).
    peak_index : int
        Where that peak is.
    """

    start: int
    frequency_hz: float
    growth: float
    cycles: int
    peak: float
    peak_index: int


def half_cycles(x: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Cut ``x`` at its sign changes; return each half-cycle's start, length and peak.

    The stretch before the first sign change and the one after the last are left out
    (they are not whole half-cycles); exact zeros take the sign before them.

    Returns
    -------
    start, length, peak : ndarray
        Index of each half-cycle's first value, its number of values, and its largest
        ``|x|``.
    """
    x = np.asarray(x, dtype=float)
    sign = np.sign(x)
    held = np.maximum.accumulate(np.where(sign != 0.0, np.arange(sign.size), 0))
    sign = sign[held]  # a zero takes the sign before it (leading zeros stay 0)
    cuts = np.flatnonzero((sign[1:] != sign[:-1]) & (sign[:-1] != 0.0)) + 1
    if cuts.size < 2:
        return np.zeros(0), np.zeros(0), np.zeros(0)
    starts, ends = cuts[:-1], cuts[1:]
    peaks = np.maximum.reduceat(np.abs(x), cuts)[:-1]  # over [cuts[i], cuts[i + 1])
    return starts.astype(float), (ends - starts).astype(float), peaks


def growing_oscillation(x: FloatArray, h: float) -> Oscillation | None:
    """Return the first growing oscillation of ``x`` (see the module), or None.

    Parameters
    ----------
    x : ndarray, shape (n,)
        A velocity error [rad/s or m/s], sampled every ``h``.
    h : float
        Sampling interval [s] (the simulator's substep).
    """
    starts, lengths, peaks = half_cycles(x)
    found = [f for size in WINDOWS if peaks.size >= size
             for f in [_first_growing(starts, lengths, peaks, h, size)] if f is not None]
    if not found:
        return None
    first, frequency, growth, cycles = min(found)
    k = first + int(np.argmax(np.abs(x[first:])))
    return Oscillation(first, frequency, growth, cycles, float(abs(x[k])), k)


def _first_growing(starts: FloatArray, lengths: FloatArray, peaks: FloatArray, h: float,
                   size: int) -> tuple[int, float, float, int] | None:
    """Return the first window of ``size`` half-cycles that grows: start, Hz, growth, cycles.

    The sums over every window come from cumulative sums (one pass per window size).
    """
    t = (starts + 0.5 * lengths) * h
    t = t - t[0]  # small numbers: the differences of sums below keep their digits
    y = np.log(peaks)

    def window_sums(v: FloatArray) -> FloatArray:
        c = np.concatenate(([0.0], np.cumsum(v)))
        return c[size:] - c[:-size]

    st, sy, stt, sty = (window_sums(v) for v in (t, y, t * t, t * y))
    sl, sll = window_sums(lengths), window_sums(lengths * lengths)
    slope = (size * sty - st * sy) / (size * stt - st * st)  # least squares, per window
    first, last = t[:t.size - size + 1], t[size - 1:]
    growth = np.exp(slope * (last - first))
    mean_length = sl / size
    omega = np.pi / (mean_length * h)
    end = np.exp(sy / size + slope * (last - st / size)) / omega  # the fit at the window's end
    spread = np.sqrt(np.maximum(sll / size - mean_length ** 2, 0.0))
    hits = np.flatnonzero((spread <= REGULARITY * mean_length) & (growth >= GROWTH)
                          & (end >= FLOOR))
    if hits.size == 0:
        return None
    i = int(hits[0])
    trough = i + int(np.argmin(peaks[i:i + size]))  # where the growth rises from
    return int(starts[trough]), float(omega[i]) / (2.0 * math.pi), float(growth[i]), size // 2


__all__ = ["FLOOR", "GROWTH", "REGULARITY", "WINDOWS", "Oscillation", "growing_oscillation",
           "half_cycles"]
