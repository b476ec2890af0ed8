"""Sweep files (YAML): which keys of an experiment file to vary, and how.

A sweep file names a *base* experiment file and the keys to replace in it, as dotted
paths into the file (``follower.base.position.0``: list items by index)::

    name: follower_base_map
    base: ../puma_beam_limits.yaml     # relative to the sweep file
    set:                               # the same replacement at every point
      controller.duration: 5
    grid:                              # every combination of these values
      follower.base.position.0: [200, 300, 400]
      solver.name: [nullspace, "qp:daqp"]
    paired:                            # keys that change with a grid key: a value for
      follower.base.position.0:        # each of its values, in order
        controller.duration: [4, 5, 6]
    random:                            # n samples (times each grid point)
      n: 20
      seed: 1
      controller.grasp_speed_max: {uniform: [50, 150]}
    repeat: 1                          # rollouts per point (step timings pooled)
    labels:                            # axis labels of the maps (default: from the key)
      follower.base.position.0: "follower base x [mm]"

Values are in the base file's units. This module reads and checks the sweep file itself
and expands it into points; whether each point makes a valid experiment is checked by
:mod:`.points`.
"""

from __future__ import annotations

import itertools
import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ConfigError

#: Keys of a sweep file.
SWEEP_KEYS = ("name", "description", "base", "set", "grid", "paired", "random", "repeat",
              "labels")

#: How a random key is drawn: ``uniform: [lo, hi]``, ``normal: [mean, sd]``,
#: ``choice: [a, b, ...]``.
DISTRIBUTIONS = ("uniform", "normal", "choice")

#: Most points one sweep may have.
MAX_POINTS = 100_000

#: Most rollouts of one point (``repeat``).
MAX_REPEAT = 1_000

#: Most rollouts of one sweep: points times ``repeat``.
MAX_ROLLOUTS = 1_000_000


@dataclass(frozen=True)
class RandomKey:
    """One key drawn at random.

    Attributes
    ----------
    key : str
        Dotted key path into the experiment file.
    kind : str
        One of :data:`DISTRIBUTIONS`.
    args : tuple
        ``(lo, hi)``, ``(mean, sd)`` or the choices.
    """

    key: str
    kind: str
    args: tuple[Any, ...]


@dataclass(frozen=True)
class SweepSpec:
    """A checked sweep file.

    Attributes
    ----------
    path : str
        The sweep file.
    name : str
        The sweep's name (default: the file's stem).
    base : Path
        The base experiment file (resolved against the sweep file's folder).
    description : str
        Free text.
    fixed : dict
        Replacements applied at every point (the file's ``set``), before the swept ones.
    grid : dict
        Values of each grid key, in file order.
    paired : dict
        Grid key -> {key: values}: keys that take the i-th of their values wherever the
        grid key takes its i-th (a distance kept fixed while the speed varies, say).
    random_n : int
        Random samples (0: no ``random`` section).
    random_seed : int
        Seed of the random samples (required with ``random``: a sweep must expand to
        the same points when it is run again, to resume).
    random : tuple of RandomKey
        The random keys, in file order.
    repeat : int
        Rollouts per point (at most :data:`MAX_REPEAT`, and at most
        :data:`MAX_ROLLOUTS` for the whole sweep); their step timings are pooled.
    labels : dict
        Swept key -> the label of its map axis, as the file gives them (the others are
        made from the key, see :mod:`.labels`).
    """

    path: str
    name: str
    base: Path
    description: str = ""
    fixed: dict[str, Any] = field(default_factory=dict)
    grid: dict[str, list[Any]] = field(default_factory=dict)
    paired: dict[str, dict[str, list[Any]]] = field(default_factory=dict)
    random_n: int = 0
    random_seed: int = 0
    random: tuple[RandomKey, ...] = ()
    repeat: int = 1
    labels: dict[str, str] = field(default_factory=dict)

    @property
    def axes(self) -> list[str]:
        """The grid keys, then the random keys: the keys varied independently (map axes)."""
        return [*self.grid, *(r.key for r in self.random)]

    @property
    def swept_keys(self) -> list[str]:
        """The axes, then the paired keys (the table's value columns)."""
        return [*self.axes, *(k for keys in self.paired.values() for k in keys)]


@dataclass(frozen=True)
class Point:
    """One point of a sweep: its number and the value of every swept key.

    Attributes
    ----------
    index : int
        Position in the sweep (0-based; grid order, then random samples).
    values : dict
        Swept key -> value, in file units.
    """

    index: int
    values: dict[str, Any]


def _error(spec_path: str, message: str, key: str | None = None,
           valid: tuple[str, ...] | list[str] = ()) -> ConfigError:
    return ConfigError(message, path=spec_path, key=key, valid=valid)


def _is_number(value: Any) -> bool:
    return (isinstance(value, (int, float)) and not isinstance(value, bool)
            and math.isfinite(value))


def check_key_path(key: Any, spec_path: str, section: str) -> str:
    """Return ``key`` if it is a dotted key path, else raise naming the section."""
    if not isinstance(key, str) or not key or any(not p.strip() for p in key.split(".")):
        raise _error(spec_path, f"'{section}' needs dotted key paths such as "
                     f"follower.base.position.0, got {key!r}", key=section)
    return key


def _positive_int(value: Any, spec_path: str, key: str, cap: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < 1:
        raise _error(spec_path, f"must be a whole number >= 1, got {value!r}", key=key)
    if value > cap:
        raise _error(spec_path, f"is {value:,}; at most {cap:,}", key=key)
    return value


def _mapping(value: Any, spec_path: str, key: str) -> dict[str, Any]:
    if not isinstance(value, dict):
        raise _error(spec_path, f"must be a mapping of dotted keys to values, got "
                     f"{type(value).__name__}", key=key)
    return value


def _grid(raw: Any, spec_path: str) -> dict[str, list[Any]]:
    out: dict[str, list[Any]] = {}
    for key, values in _mapping(raw, spec_path, "grid").items():
        check_key_path(key, spec_path, "grid")
        if not isinstance(values, list) or not values:
            raise _error(spec_path, f"grid values must be a non-empty list, got {values!r}",
                         key=key)
        seen = [json.dumps(v, sort_keys=True) for v in values]
        twice = next((values[i] for i, s in enumerate(seen) if s in seen[:i]), None)
        if len(set(seen)) != len(seen):
            raise _error(spec_path, f"grid value {twice!r} is given twice", key=key)
        out[key] = list(values)
    return out


def _paired(raw: Any, spec_path: str, grid: dict[str, list[Any]]
            ) -> dict[str, dict[str, list[Any]]]:
    """Check the ``paired`` section: for grid keys, a list of values as long as theirs."""
    out: dict[str, dict[str, list[Any]]] = {}
    for gkey, keys in _mapping(raw, spec_path, "paired").items():
        if gkey not in grid:
            raise _error(spec_path, "pairs keys with a grid key, and this is not one",
                         key=f"paired.{gkey}", valid=list(grid))
        out[gkey] = {}
        for key, values in _mapping(keys, spec_path, f"paired.{gkey}").items():
            check_key_path(key, spec_path, f"paired.{gkey}")
            n = len(grid[gkey])
            if not isinstance(values, list) or len(values) != n:
                raise _error(spec_path, f"needs a list of {n} values, one for each value "
                             f"of '{gkey}', got {values!r}", key=f"paired.{gkey}.{key}")
            out[gkey][key] = list(values)
    return out


def _random_key(key: str, spec: Any, spec_path: str) -> RandomKey:
    if not (isinstance(spec, dict) and len(spec) == 1):
        raise _error(spec_path, f"a random key takes one distribution, e.g. "
                     f"{{uniform: [lo, hi]}}; got {spec!r}", key=key, valid=DISTRIBUTIONS)
    kind, args = next(iter(spec.items()))
    if kind not in DISTRIBUTIONS:
        raise _error(spec_path, f"unknown distribution {kind!r}", key=key, valid=DISTRIBUTIONS)
    if not isinstance(args, list) or not args:
        raise _error(spec_path, f"{kind} takes a list, got {args!r}", key=key)
    if kind == "choice":
        return RandomKey(key, kind, tuple(args))
    if len(args) != 2 or not all(_is_number(a) for a in args):
        what = "[lo, hi]" if kind == "uniform" else "[mean, sd]"
        raise _error(spec_path, f"{kind} takes two finite numbers {what}, got {args!r}",
                     key=key)
    a, b = float(args[0]), float(args[1])
    if kind == "uniform" and not a < b:
        raise _error(spec_path, f"uniform needs lo < hi, got [{a:g}, {b:g}]", key=key)
    if kind == "normal" and not b > 0:
        raise _error(spec_path, f"normal needs a standard deviation > 0, got {b:g}", key=key)
    return RandomKey(key, kind, (a, b))


def _random(raw: Any, spec_path: str) -> tuple[int, int, tuple[RandomKey, ...]]:
    section = _mapping(raw, spec_path, "random")
    if "n" not in section:
        raise _error(spec_path, "missing the number of samples 'n'", key="random.n")
    if "seed" not in section:
        raise _error(spec_path, "missing 'seed': a sweep must draw the same points when "
                     "it is run again (to resume)", key="random.seed")
    n = _positive_int(section["n"], spec_path, "random.n", MAX_POINTS)
    seed = section["seed"]
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise _error(spec_path, f"must be a whole number >= 0, got {seed!r}",
                     key="random.seed")
    keys = tuple(_random_key(check_key_path(k, spec_path, "random"), v, spec_path)
                 for k, v in section.items() if k not in ("n", "seed"))
    if not keys:
        raise _error(spec_path, "names no key to draw (add e.g. "
                     "'controller.grasp_speed_max: {uniform: [50, 150]}')", key="random")
    return n, seed, keys


def _labels(raw: Any, spec_path: str, swept: list[str]) -> dict[str, str]:
    """Check the ``labels`` section: text for swept keys only."""
    if not isinstance(raw, dict):
        raise _error(spec_path, f"must be a mapping of swept keys to axis labels, got "
                     f"{type(raw).__name__}", key="labels")
    for key, text in raw.items():
        if key not in swept:
            raise _error(spec_path, "is not a swept key", key=f"labels.{key}", valid=swept)
        if not isinstance(text, str) or not text.strip():
            raise _error(spec_path, f"must be non-empty text, got {text!r}",
                         key=f"labels.{key}")
    return dict(raw)


def _check_overlaps(spec_path: str, fixed: dict[str, Any], swept: list[str]) -> None:
    """Refuse a key swept twice, or swept together with a part of it, or also fixed."""
    for i, a in enumerate(swept):
        if a in fixed:
            raise _error(spec_path, "is both set and swept; give it in one place", key=a)
        for b in swept[i + 1:]:
            if a == b:
                raise _error(spec_path, "is swept twice (in grid, paired or random)", key=a)
            if b.startswith(a + ".") or a.startswith(b + "."):
                raise _error(spec_path, f"is swept together with '{b}', a part of it or "
                             "the whole that holds it; sweep one of them", key=a)


def parse_sweep(data: Any, spec_path: str) -> SweepSpec:
    """Check a loaded sweep document and return it as a :class:`SweepSpec`.

    Raises
    ------
    ConfigError
        Naming the sweep file and the offending key (with the valid keys or choices).
    """
    if not isinstance(data, dict):
        raise _error(spec_path, "a sweep file must be a mapping of keys (base, grid, "
                     "random, ...)")
    unknown = [k for k in data if k not in SWEEP_KEYS]
    if unknown:
        raise _error(spec_path, "unknown key", key=str(unknown[0]), valid=SWEEP_KEYS)
    if "base" not in data:
        raise _error(spec_path, "missing the base experiment file", key="base")
    if not isinstance(data["base"], str) or not data["base"]:
        raise _error(spec_path, f"must be the path of an experiment file, got "
                     f"{data['base']!r}", key="base")
    if "grid" not in data and "random" not in data:
        raise _error(spec_path, "sweeps nothing: give 'grid', 'random' or both",
                     valid=("grid", "random"))
    name = data.get("name", Path(spec_path).stem)
    if not isinstance(name, str) or not name.strip():
        raise _error(spec_path, f"must be non-empty text, got {name!r}", key="name")
    description = data.get("description", "")
    if not isinstance(description, str):
        raise _error(spec_path, "must be text", key="description")
    fixed = {check_key_path(k, spec_path, "set"): v
             for k, v in _mapping(data.get("set", {}) or {}, spec_path, "set").items()}
    grid = _grid(data["grid"], spec_path) if "grid" in data else {}
    n, seed, rand = _random(data["random"], spec_path) if "random" in data else (0, 0, ())
    paired = _paired(data["paired"], spec_path, grid) if "paired" in data else {}
    swept = [*grid, *(r.key for r in rand), *(k for keys in paired.values() for k in keys)]
    _check_overlaps(spec_path, fixed, swept)
    labels = _labels(data["labels"], spec_path, swept) if "labels" in data else {}
    repeat = _positive_int(data.get("repeat", 1), spec_path, "repeat", MAX_REPEAT)
    total = math.prod(len(v) for v in grid.values()) * max(n, 1)
    if total > MAX_POINTS:
        raise _error(spec_path, f"expands to {total:,} points; a sweep has at most "
                     f"{MAX_POINTS:,}", key="grid" if grid else "random.n")
    if total * repeat > MAX_ROLLOUTS:
        raise _error(spec_path, f"{total:,} points x {repeat:,} rollouts is "
                     f"{total * repeat:,} rollouts; a sweep runs at most {MAX_ROLLOUTS:,}",
                     key="repeat")
    base = Path(data["base"])
    if not base.is_absolute():
        base = Path(spec_path).parent / base
    return SweepSpec(path=spec_path, name=name, base=base, description=description,
                     fixed=fixed, grid=grid, paired=paired, random_n=n, random_seed=seed,
                     random=rand, repeat=repeat, labels=labels)


def load_sweep(path: str | Path) -> SweepSpec:
    """Read and check a sweep file (YAML read as experiment files are).

    Raises
    ------
    ConfigError
        Missing or unreadable file, invalid YAML, or an invalid sweep (naming the key).
    """
    from ..experiments.yaml_file import read_yaml_document

    return parse_sweep(read_yaml_document(path), str(path))


def _draw(rng: np.random.Generator, r: RandomKey) -> Any:
    if r.kind == "uniform":
        return float(rng.uniform(r.args[0], r.args[1]))
    if r.kind == "normal":
        return float(rng.normal(r.args[0], r.args[1]))
    return r.args[int(rng.integers(len(r.args)))]


def expand(spec: SweepSpec) -> list[Point]:
    """Return the sweep's points.

    The grid's combinations (last key fastest; a paired key takes the value at the
    position of its grid key's), each with every random sample (drawn once, in order,
    from ``random.seed``).
    """
    rng = np.random.default_rng(spec.random_seed)
    samples: list[dict[str, Any]] = [
        {r.key: _draw(rng, r) for r in spec.random} for _ in range(spec.random_n)] or [{}]
    keys = list(spec.grid)
    points: list[Point] = []
    for at in itertools.product(*(range(len(v)) for v in spec.grid.values())):
        grid_values = {k: spec.grid[k][i] for k, i in zip(keys, at, strict=True)}
        for gkey, paired in spec.paired.items():
            i = at[keys.index(gkey)]
            grid_values.update({k: values[i] for k, values in paired.items()})
        for sample in samples:
            points.append(Point(len(points), {**grid_values, **sample}))
    return points
