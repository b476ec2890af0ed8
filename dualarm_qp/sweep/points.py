"""A sweep's points as experiments: keys replaced in the base file, checked, keyed.

Every point is the base experiment file with the sweep's ``set`` keys and then its swept
keys replaced, checked exactly as ``dualarm-qp run`` checks a file (the schema of
:func:`~dualarm_qp.experiments.config.parse_config`, then
:func:`~dualarm_qp.experiments.setup.build_experiment`, then the solver). A bad key or
value anywhere stops the sweep before anything runs, with a
:class:`~dualarm_qp.errors.ConfigError` naming the sweep file and the key.

One outcome of the checks is not bad input but a result: a start pose that the inverse
kinematics cannot reach (a follower base too far from the object, an IK branch that does
not exist there). Such a point is recorded as failed with the criterion
:data:`START_UNREACHABLE`, so that a map shows where an arm cannot even start. When no
point at all can start, the sweep is bad input after all.

Each point is keyed by its content (the whole experiment document after the
replacements, the repeat count, the record format) and the code digest of the package
(:func:`~dualarm_qp.bench.runner.code_digest`), so a rerun skips what is stored and
changed code computes afresh.
"""

from __future__ import annotations

import copy
import hashlib
import json
import re
from dataclasses import dataclass
from typing import Any

from ..errors import ConfigError, DualArmError
from .spec import Point, SweepSpec, expand

#: Version of the stored record's fields; part of every point's key.
RECORD_FORMAT = 2

#: Criterion of a point whose start pose cannot be reached.
START_UNREACHABLE = "start_unreachable"

#: Keys whose ConfigError from ``build_experiment`` means "the start cannot be reached".
_START_KEYS = tuple(f"{role}.initial.{form}" for role in ("leader", "follower")
                    for form in ("ik_branch", "near", "joints"))

#: The key of an obstacle's pose (its start overlap is a start failure too).
_OBSTACLE_POSE = re.compile(r"scene\.obstacles\.\d+\.pose")


@dataclass(frozen=True)
class PointTask:
    """A point ready to run: plain data, cheap to send to a worker.

    Attributes
    ----------
    index : int
        The point's number in the sweep.
    key : str
        Content and code digest (hex): the point's identity in the store.
    values : dict
        Swept key -> value (file units).
    document : dict
        The whole experiment document of the point.
    base_path : str
        The base experiment file (relative file names in the document resolve against
        its folder).
    repeat : int
        Rollouts to run.
    start_failure : str or None
        Why the start pose cannot be reached (the point is not run), or None.
    """

    index: int
    key: str
    values: dict[str, Any]
    document: dict[str, Any]
    base_path: str
    repeat: int
    start_failure: str | None = None


def set_key(document: Any, key: str, value: Any, *, spec_path: str) -> None:
    """Replace the value at dotted ``key`` in ``document`` (in place).

    Missing mappings on the way are created (the schema check then names a key that
    does not exist); a list item is addressed by its index.

    Raises
    ------
    ConfigError
        An index out of range, or a value on the way that is neither mapping nor list.
    """
    parts = key.split(".")
    node = document
    for depth, part in enumerate(parts):
        last = depth == len(parts) - 1
        where = ".".join(parts[:depth]) or "the top level"
        if isinstance(node, list):
            if not part.lstrip("-").isdigit():
                raise ConfigError(f"'{where}' is a list: address its items by index "
                                  f"(0 to {len(node) - 1}), not {part!r}",
                                  path=spec_path, key=key)
            i = int(part)
            if not 0 <= i < len(node):
                raise ConfigError(f"index {i} is out of range: '{where}' has {len(node)} "
                                  f"items (0 to {len(node) - 1})", path=spec_path, key=key)
            if last:
                node[i] = copy.deepcopy(value)
            else:
                node = node[i]
        elif isinstance(node, dict):
            if last:
                node[part] = copy.deepcopy(value)
            else:
                if node.get(part) is None:
                    node[part] = {}
                node = node[part]
        else:
            raise ConfigError(f"'{where}' is the value {node!r}, not a mapping or a list, "
                              "so it has no part to replace (set it whole, e.g. in 'set')",
                              path=spec_path, key=key)


def point_document(base: dict[str, Any], spec: SweepSpec, point: Point) -> dict[str, Any]:
    """Return the base document with the ``set`` and then the point's keys replaced."""
    doc = copy.deepcopy(base)
    for key, value in spec.fixed.items():
        set_key(doc, key, value, spec_path=spec.path)
    for key, value in point.values.items():
        set_key(doc, key, value, spec_path=spec.path)
    return doc


def point_key(document: dict[str, Any], repeat: int, code: str) -> str:
    """Return the point's identity in the store: a digest of its content and the code."""
    blob = json.dumps({"document": document, "repeat": repeat, "format": RECORD_FORMAT,
                       "code": code}, sort_keys=True, separators=(",", ":"), default=str)
    return hashlib.sha256(blob.encode()).hexdigest()[:24]


def _owner(err: ConfigError, spec: SweepSpec, point: Point) -> tuple[str, Any] | None:
    """Return the set or swept key (and its value) that an error belongs to."""
    if err.key is None:
        return None
    owners = [*point.values.items(), *spec.fixed.items()]
    for key, value in owners:
        if err.key == key or err.key.startswith(key + ".") or key.startswith(err.key + "."):
            return key, value
    return None


def _bare(err: ConfigError, *, keep_key: bool = False) -> str:
    """Return the message of ``err`` without its file and key prefix and valid choices.

    With ``keep_key`` the key and the valid choices stay.
    """
    text = str(err)
    if err.path is not None:
        text = text.removeprefix(f"{err.path}:").lstrip()
    if keep_key:
        return text
    if err.key is not None:
        text = text.removeprefix(f"key '{err.key}':").lstrip()
    if err.valid:
        text = text.removesuffix(f" (valid: {', '.join(err.valid)})")
    return text


def _as_sweep_error(err: ConfigError, spec: SweepSpec, point: Point) -> ConfigError:
    """Name the sweep file and the key when the error comes from a replaced value."""
    owner = _owner(err, spec, point)
    if owner is None:
        return err  # the base file's own problem: it names the base file
    key, value = owner
    where = "set" if key in spec.fixed else f"point {point.index}"
    inner = "" if err.key in (None, key) else f" (at {err.key})"
    return ConfigError(f"value {json.dumps(value)} ({where}){inner}: {_bare(err)}",
                       path=spec.path, key=key, valid=err.valid)


def is_start_failure(err: ConfigError) -> bool:
    """Whether a ``build_experiment`` error means the start pose cannot be reached.

    An arm's start cannot be solved, or an obstacle occupies the arms' start posture
    (``scene.obstacles.<i>.pose``: it overlaps an arm or the object there).
    """
    return err.key in _START_KEYS or bool(
        err.key and _OBSTACLE_POSE.fullmatch(err.key)
        and "at the start" in str(err))


def check_point(doc: dict[str, Any], spec: SweepSpec, point: Point,
                solvers_checked: set[str]) -> str | None:
    """Check one point as ``dualarm-qp run`` would; return a start failure or None.

    Parameters
    ----------
    solvers_checked : set of str
        Solver specifications already built once (filled in): each distinct one is built
        once, so an unknown or missing solver is found without building it per point.

    Raises
    ------
    ConfigError
        Bad input, naming the sweep file and the key it comes from.
    """
    from ..experiments.config import parse_config
    from ..experiments.setup import build_experiment

    base = str(spec.base)
    try:
        cfg = parse_config(doc, base)
        exp = build_experiment(cfg, base)
    except ConfigError as err:
        if is_start_failure(err):
            return _bare(err, keep_key=True)
        raise _as_sweep_error(err, spec, point) from None
    solver = json.dumps(doc.get("solver"), sort_keys=True, default=str)
    if solver not in solvers_checked:
        try:
            exp.controller()
        except DualArmError as err:
            raise _as_sweep_error(ConfigError(str(err), path=base, key="solver.name"),
                                  spec, point) from None
        solvers_checked.add(solver)
    return None


def prepare_points(spec: SweepSpec, code: str) -> list[PointTask]:
    """Expand the sweep and check every point (see the module docstring).

    Parameters
    ----------
    spec : SweepSpec
        The sweep.
    code : str
        Code digest of the package (part of each point's key).

    Raises
    ------
    ConfigError
        A bad key or value (naming the sweep file and the key), a missing base file
        (naming the sweep file, ``base`` and the path), a base file that is not an
        experiment file, or a sweep in which no point can start.
    """
    from ..experiments.yaml_file import read_yaml_document

    if not spec.base.is_file():  # the sweep's own value: name the sweep file and the key
        what = "is a folder, not a file" if spec.base.is_dir() else "file not found"
        raise ConfigError(f"{what}: {spec.base}", path=spec.path, key="base")
    base = read_yaml_document(spec.base)
    if not isinstance(base, dict):
        raise ConfigError("the base experiment file must be a mapping of keys",
                          path=str(spec.base))
    tasks = []
    checked: set[str] = set()
    first_failure: tuple[Point, str] | None = None
    for point in expand(spec):
        doc = point_document(base, spec, point)
        failure = check_point(doc, spec, point, checked)
        if failure is not None and first_failure is None:
            first_failure = (point, failure)
        tasks.append(PointTask(point.index, point_key(doc, spec.repeat, code), point.values,
                               doc, str(spec.base), spec.repeat, failure))
    if first_failure is not None and all(t.start_failure for t in tasks):
        point, failure = first_failure
        raise ConfigError(f"no point can start; the first, {json.dumps(point.values)}: "
                          f"{failure}", path=spec.path)
    return tasks
