"""A lane of the lane figures (:mod:`.lanes`): one joint's values scaled to its limits.

A lane is one unit high; its limits lie :data:`LIMIT` above and below its middle, values
beyond them are drawn up to :data:`CLIP` from it. :func:`range_lane` and :func:`speed_lane`
give a joint's lane against its range or its speed limit, with the label beside it.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .canvas import FloatArray, tick_text

#: Where a lane's limits lie: ``LIMIT`` above and below the lane's middle (a lane is
#: one unit high).
LIMIT = 0.33

#: Values are clipped this far from the lane's middle (just inside its edge).
CLIP = 0.48


@dataclass(frozen=True)
class Lane:
    """One joint's lane: what it draws and the values on its two limit lines.

    Attributes
    ----------
    name : str
        The joint's column (``"qf3"``, ``"qf_dot3"``): the artists' gids end with it.
    label : str
        The text beside the lane.
    low, high : float
        The values (display units) on the lower and the upper limit line.
    limits : tuple of float
        The finite limits (display units), drawn as dashed lines.
    """

    name: str
    label: str
    low: float
    high: float
    limits: tuple[float, ...]

    def scale(self, values: Any, middle: float) -> FloatArray:
        """Return ``values`` (display units) as heights in the lane centred at ``middle``."""
        v = np.asarray(values, dtype=float)
        y = middle + LIMIT * (2.0 * (v - self.low) / (self.high - self.low) - 1.0)
        return np.asarray(np.clip(y, middle - CLIP, middle + CLIP))

    def height(self, value: float, middle: float) -> float:
        """Return the height of one value (display units) in the lane, unclipped."""
        return float(middle + LIMIT * (2.0 * (value - self.low) / (self.high - self.low) - 1.0))


def _span(values: Sequence[Any], lo: float, hi: float) -> tuple[float, float]:
    """Return the lane's ``(low, high)``: the finite limits, else the values reached."""
    data = np.concatenate([np.asarray(v, dtype=float).ravel() for v in values])
    data = data[np.isfinite(data)]
    low = lo if np.isfinite(lo) else (float(data.min()) if data.size else -1.0)
    high = hi if np.isfinite(hi) else (float(data.max()) if data.size else 1.0)
    if np.isfinite(lo) and not np.isfinite(hi) and high <= low:
        high = low + max(abs(low), 1.0)
    if np.isfinite(hi) and not np.isfinite(lo) and low >= high:
        low = high - max(abs(high), 1.0)
    if high <= low:  # no limit and one value: a lane around it
        pad = max(abs(low), 1.0)
        low, high = low - pad, high + pad
    return float(low), float(high)


def _value(v: float, digits: int = 4) -> str:
    """Return a value for a lane's label: ``digits`` significant digits, no exponent."""
    return tick_text(float(f"{v:.{digits}g}"))


def _farthest(lane: Lane, values: Sequence[Any]) -> str:
    """Name the value clipped the farthest (a second line of the label), if any was."""
    data = np.concatenate([np.asarray(v, dtype=float).ravel() for v in values])
    data = data[np.isfinite(data)]
    if not data.size:
        return ""
    mid = 0.5 * (lane.low + lane.high)
    far = float(data[np.argmax(np.abs(data - mid))])
    return f"\nreaches {_value(far, 3)}" if abs(lane.height(far, 0.0)) > CLIP else ""


def range_lane(name: str, joint: str, values: Any, lo: float, hi: float) -> Lane:
    """Return the lane of a joint against its range ``[lo, hi]`` (display units, or inf).

    Its label: the joint (``q3``) and its range (``-45 .. 225``, ``+-160``, ``>= -45``,
    ``no range``), then the farthest value reached when one is clipped.
    """
    low, high = _span([values], lo, hi)
    if np.isfinite(lo) and np.isfinite(hi):
        text = (f"\N{PLUS-MINUS SIGN}{_value(hi)}" if lo == -hi
                else f"{_value(lo)} .. {_value(hi)}")
    elif np.isfinite(lo) or np.isfinite(hi):
        text = f">= {_value(lo)}" if np.isfinite(lo) else f"<= {_value(hi)}"
    else:
        text = "no range"
    lane = Lane(name, "", low, high, tuple(v for v in (lo, hi) if np.isfinite(v)))
    return Lane(name, f"{joint} {text}{_farthest(lane, [values])}", low, high, lane.limits)


def speed_lane(name: str, joint: str, values: Sequence[Any], limit: float) -> Lane:
    """Return the lane of a rate against ``+-limit`` (display units; infinite: no limit).

    Its label: the joint and ``+-limit``, then the farthest value reached when one is
    clipped. Without a limit the lane is scaled to the largest ``|value|``, and says so.
    """
    if np.isfinite(limit) and limit > 0:
        lane = Lane(name, "", -limit, limit, (-limit, limit))
        text = f"\N{PLUS-MINUS SIGN}{_value(limit)}"
    else:
        data = np.concatenate([np.abs(np.asarray(v, dtype=float)).ravel() for v in values])
        peak = float(np.nanmax(data, initial=0.0)) if data.size else 0.0
        peak = peak if np.isfinite(peak) and peak > 0 else 1.0
        lane = Lane(name, "", -peak, peak, ())
        text = f"no limit\nscaled to \N{PLUS-MINUS SIGN}{_value(peak, 3)}"
    return Lane(name, f"{joint} {text}{_farthest(lane, values)}", lane.low, lane.high,
                lane.limits)


__all__ = ["CLIP", "LIMIT", "Lane", "range_lane", "speed_lane"]
