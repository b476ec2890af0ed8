"""Reading an experiment file's YAML safely: before any schema check.

The same rules for every YAML file the library reads (experiment files, sweep files):
a size limit, UTF-8 text (a clear error for UTF-16/32 or binary), YAML 1.2 scalars
(``1e-9`` is a number; only ``true``/``false`` are booleans), no key given twice in one
mapping, and a nesting limit (PyYAML's loader recurses). Each problem is a
:class:`~dualarm_qp.errors.ConfigError` naming the file and, where it can, the key path.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import yaml

from ..errors import ConfigError

#: Largest experiment file read, in bytes.
MAX_FILE_BYTES = 1_000_000

#: Deepest nesting of mappings and lists in an experiment file (the schema needs 6).
MAX_DEPTH = 32


def _plain_key(keys: tuple[str, ...]) -> str:
    """Return a key path as written (``a.b.0``): for files without a schema."""
    return ".".join(keys)


class _Loader(yaml.SafeLoader):
    """SafeLoader with YAML 1.2 scalars.

    ``1e-9`` is a number (YAML 1.1 reads it as text) and only ``true``/``false`` are
    booleans (YAML 1.1 also takes yes, no, on, off).
    """


_Loader.yaml_implicit_resolvers = {
    first: [(tag, rx) for tag, rx in resolvers if tag != "tag:yaml.org,2002:bool"]
    for first, resolvers in yaml.SafeLoader.yaml_implicit_resolvers.items()
}
_Loader.add_implicit_resolver(
    "tag:yaml.org,2002:bool", re.compile(r"^(?:true|True|TRUE|false|False|FALSE)$"),
    list("tTfF"))


_Loader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:[0-9][0-9_]*)(?:\.[0-9_]*)?[eE][-+]?[0-9]+$"),
    list("-+0123456789"))


def yaml_scalar(text: str) -> Any:
    """Read one YAML scalar (``1e-9``, ``true``, ``abc``) as an experiment file would.

    Raises
    ------
    ValueError
        ``text`` is not one scalar (a list, a mapping or broken YAML).
    """
    try:
        value = yaml.load(text, Loader=_Loader)
    except yaml.YAMLError as err:
        raise ValueError(f"not a valid YAML value: {getattr(err, 'problem', err)}") from None
    if isinstance(value, (dict, list)):
        raise ValueError("must be a single value, not a list or a mapping")
    return value


def _decode(raw: bytes, path: str) -> str:
    """Return the file's text, or raise a ConfigError saying where the encoding is wrong."""
    boms = {b"\xff\xfe\x00\x00": "UTF-32", b"\x00\x00\xfe\xff": "UTF-32",
            b"\xff\xfe": "UTF-16", b"\xfe\xff": "UTF-16"}
    for bom, name in boms.items():
        if raw.startswith(bom):
            raise ConfigError(f"the file is {name} encoded; save it as UTF-8", path=path)
    if b"\x00" in raw:
        line = raw[: raw.index(b"\x00")].count(b"\n") + 1
        raise ConfigError(f"the file holds a NUL byte at line {line}: it is binary or "
                          "UTF-16/32 without a byte-order mark; save it as UTF-8 text",
                          path=path)
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as err:
        line = raw[: err.start].count(b"\n") + 1
        column = err.start - (raw.rfind(b"\n", 0, err.start) + 1) + 1
        key = _key_at_line(raw.decode("utf-8", errors="replace"), line)
        raise ConfigError(f"the file is not UTF-8 text: byte 0x{raw[err.start]:02x} at line "
                          f"{line}, column {column}; save it as UTF-8",
                          path=path, key=key) from None


class _Frame:
    """An open mapping or list while walking the YAML events."""

    __slots__ = ("current", "expect_key", "is_key", "is_map", "keys")

    def __init__(self, is_map: bool, is_key: bool) -> None:
        self.is_map = is_map
        self.current: str | int | None = None if is_map else 0
        self.expect_key = is_map
        self.keys: set[str] = set()
        self.is_key = is_key


def _walk(text: str, path: str, schema_key: Callable[[tuple[str, ...]], str] = _plain_key
          ) -> Iterator[tuple[tuple[str, ...], yaml.Event]]:
    """Yield every YAML event with its key path, without recursion (any depth).

    Raises ConfigError for nesting deeper than :data:`MAX_DEPTH` (PyYAML's loader
    recurses and would end in a RecursionError) and for a key given twice in one
    mapping (PyYAML keeps the last one silently).
    """
    stack: list[_Frame] = []

    def where() -> tuple[str, ...]:
        return tuple(str(f.current) for f in stack if f.current is not None)

    def value_done() -> None:
        if stack:
            top = stack[-1]
            if top.is_map:
                top.expect_key = True
            else:
                assert isinstance(top.current, int)
                top.current += 1

    for event in yaml.parse(text, Loader=_Loader):
        top = stack[-1] if stack else None
        if isinstance(event, (yaml.ScalarEvent, yaml.AliasEvent)):
            if top is not None and top.is_map and top.expect_key:
                key = (str(event.value) if isinstance(event, yaml.ScalarEvent)
                       else f"*{event.anchor}")
                if key in top.keys and key != "<<":
                    line = event.start_mark.line + 1 if event.start_mark else 0
                    raise ConfigError(f"the key is given twice in one mapping (again at "
                                      f"line {line}); give it once", path=path,
                                      key=".".join((*where()[:-1], key))
                                      if top.current is not None else key)
                top.keys.add(key)
                top.current = key
                top.expect_key = False
                yield where(), event
            else:
                yield where(), event
                value_done()
        elif isinstance(event, (yaml.MappingStartEvent, yaml.SequenceStartEvent)):
            if len(stack) >= MAX_DEPTH:
                line = event.start_mark.line + 1 if event.start_mark else 0
                raise ConfigError(f"nested more than {MAX_DEPTH} levels deep (line {line}); "
                                  "an experiment file needs at most 6", path=path,
                                  key=schema_key(where()) or None)
            yield where(), event
            is_key = top is not None and top.is_map and top.expect_key
            stack.append(_Frame(isinstance(event, yaml.MappingStartEvent), is_key))
        elif isinstance(event, (yaml.MappingEndEvent, yaml.SequenceEndEvent)):
            done = stack.pop()
            yield where(), event
            if done.is_key and stack:
                stack[-1].current = "?"
                stack[-1].expect_key = False
            else:
                value_done()
        else:
            yield where(), event


def _key_at_line(text: str, line: int) -> str | None:
    """Key path of the first value or key on ``line`` (1-based), or None."""
    try:
        for keys, event in _walk(text, "<text>"):
            mark = event.start_mark
            if mark is not None and mark.line + 1 >= line and keys:
                return ".".join(keys)
    except (yaml.YAMLError, ConfigError):
        pass
    return None


def _scan(text: str, path: str, schema_key: Callable[[tuple[str, ...]], str]) -> None:
    """Walk the whole document once (see :func:`_walk`) before it is constructed."""
    for _ in _walk(text, path, schema_key):
        pass


def read_yaml_document(path: str | Path, *,
                       schema_key: Callable[[tuple[str, ...]], str] = _plain_key) -> Any:
    """Read a YAML file as an experiment file is read, without checking its keys.

    The size limit, encoding, YAML 1.2 scalars, duplicate-key and depth checks of this
    module; the document comes back as plain data (mappings, lists, scalars).
    ``schema_key`` shortens a key path to the part a schema knows, for the message of a
    runaway nesting (:func:`dualarm_qp.experiments.config.load_config` passes its own).

    Raises
    ------
    ConfigError
        Missing or unreadable file, or text that is not valid YAML.
    """
    p = Path(path)
    try:
        size = p.stat().st_size
        if size > MAX_FILE_BYTES:
            raise ConfigError(f"the file is {size:,} bytes; an experiment file is at most "
                              f"{MAX_FILE_BYTES:,}", path=str(p))
        raw = p.read_bytes()
    except FileNotFoundError:
        raise ConfigError("file not found", path=str(p)) from None
    except IsADirectoryError:
        raise ConfigError("is a folder, not a file", path=str(p)) from None
    except OSError as err:
        raise ConfigError(f"cannot read file: {err.strerror}", path=str(p)) from None
    text = _decode(raw, str(p))
    try:
        _scan(text, str(p), schema_key)
        data = yaml.load(text, Loader=_Loader)
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        raise ConfigError(f"not valid YAML{where}: {getattr(err, 'problem', err)}",
                          path=str(p)) from None
    except RecursionError:
        raise ConfigError(f"nested more than {MAX_DEPTH} levels deep", path=str(p)) from None
    return data


__all__ = ["MAX_DEPTH", "MAX_FILE_BYTES", "read_yaml_document", "yaml_scalar"]
