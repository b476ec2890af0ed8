"""Axis labels of swept keys: a readable name and the unit, in the experiment file's units.

``follower.base.position.0`` in a file with ``units: {length: mm}`` is labelled
``follower base x [mm]``; ``trajectory.velocity.0`` ``object velocity x [mm/s]``. A key
without a rule here is labelled by its path (dots and underscores as spaces, no unit).
A sweep file's ``labels`` mapping replaces the label of any swept key.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping, Sequence
from typing import Any

#: Default units of an experiment file (``units`` left out), as ``docs/configuration.md``.
DEFAULT_UNITS = {"length": "m", "angle": "rad", "time": "s"}

_XYZ = ("x", "y", "z")
_RPY = ("roll", "pitch", "yaw")
_ROLE = r"(leader|follower)"


def _xyz(i: str) -> str:
    return _XYZ[int(i)] if int(i) < 3 else i


def _joint(i: str) -> str:
    return f"q{int(i) + 1}"


#: (key pattern, name from the pattern's groups, unit from the file's units or None).
_Rule = tuple[str, Callable[..., str], Callable[[Mapping[str, str]], str] | None]


def _length(u: Mapping[str, str]) -> str:
    return u["length"]


def _angle(u: Mapping[str, str]) -> str:
    return u["angle"]


def _time(u: Mapping[str, str]) -> str:
    return u["time"]


def _speed(u: Mapping[str, str]) -> str:
    return f"{u['length']}/{u['time']}"


def _turn_rate(u: Mapping[str, str]) -> str:
    return f"{u['angle']}/{u['time']}"


def _per_time(u: Mapping[str, str]) -> str:
    return f"1/{u['time']}"


_RULES: tuple[_Rule, ...] = (
    (rf"{_ROLE}\.base\.position\.(\d)", lambda r, i: f"{r} base {_xyz(i)}", _length),
    (rf"{_ROLE}\.base\.rpy\.(\d)", lambda r, i: f"{r} base {_RPY[int(i)]}", _angle),
    (rf"{_ROLE}\.tool\.position\.(\d)", lambda r, i: f"{r} tool {_xyz(i)}", _length),
    (rf"{_ROLE}\.tool\.rpy\.(\d)", lambda r, i: f"{r} tool {_RPY[int(i)]}", _angle),
    (rf"{_ROLE}\.q_min\.(\d+)", lambda r, i: f"{r} {_joint(i)} lower limit", _angle),
    (rf"{_ROLE}\.q_max\.(\d+)", lambda r, i: f"{r} {_joint(i)} upper limit", _angle),
    (rf"{_ROLE}\.qd_max\.(\d+)", lambda r, i: f"{r} {_joint(i)} speed limit", _turn_rate),
    (rf"{_ROLE}\.initial\.(?:joints|near)\.(\d+)", lambda r, i: f"{r} initial {_joint(i)}",
     _angle),
    (r"trajectory\.velocity\.(\d)", lambda i: f"object velocity {_xyz(i)}", _speed),
    (r"trajectory\.start\.position\.(\d)", lambda i: f"path start {_xyz(i)}", _length),
    (r"trajectory\.waypoints\.(\d+)\.t", lambda i: f"waypoint {i} time", _time),
    (r"object\.grasp_initial", lambda: "initial grasp", _length),
    (r"object\.leader_grasp_initial", lambda: "initial leader grasp", _length),
    (r"object\.surface\.r_(min|max)\.(\d)", lambda m, i: f"grasp range {m} {_xyz(i)}",
     _length),
    (r"object\.mass", lambda: "object mass", lambda u: "kg"),
    (r"controller\.dt", lambda: "sampling interval", _time),
    (r"controller\.duration", lambda: "duration", _time),
    (r"controller\.duration_cap", lambda: "duration cap", _time),
    (r"controller\.grasp_speed_max", lambda: "sliding speed limit", _speed),
    (r"controller\.correction_gain", lambda: "closure feedback gain", _per_time),
    (r"controller\.leader_gain", lambda: "leader feedback gain", _per_time),
    (r"controller\.centre_horizon", lambda: "centring horizon", _time),
    (r"controller\.recovery_fraction", lambda: "recovery fraction", None),
    (r"controller\.weights\.grasp", lambda: "grasp weight s7", None),
    (r"controller\.weights\.joints", lambda: "joint weight", None),
    (r"controller\.policy", lambda: "policy", None),
    (r"solver\.name", lambda: "solver", None),
)


def file_units(document: Mapping[str, Any]) -> dict[str, str]:
    """Return the units of an experiment document (its ``units``, else the defaults)."""
    given = document.get("units")
    units = dict(DEFAULT_UNITS)
    if isinstance(given, Mapping):
        units.update({k: str(v) for k, v in given.items() if k in units})
    return units


def axis_label(key: str, units: Mapping[str, str] | None = None) -> str:
    """Return the readable label of swept ``key`` (``follower base x [mm]``).

    Parameters
    ----------
    key : str
        Dotted key path into the experiment file.
    units : mapping, optional
        The file's units (``length``, ``angle``, ``time``); default
        :data:`DEFAULT_UNITS`.
    """
    units = {**DEFAULT_UNITS, **(units or {})}
    for pattern, name, unit in _RULES:
        match = re.fullmatch(pattern, key)
        if match is not None:
            text = name(*match.groups())
            return f"{text} [{unit(units)}]" if unit is not None else text
    return key.replace(".", " ").replace("_", " ")


def sweep_labels(keys: Sequence[str], units: Mapping[str, str],
                 given: Mapping[str, str] | None = None) -> dict[str, str]:
    """Return the label of every swept key: ``given`` (the sweep file's), else its own."""
    given = given or {}
    return {k: given.get(k) or axis_label(k, units) for k in keys}
