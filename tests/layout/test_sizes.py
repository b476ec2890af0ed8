"""Every module of the package fits on a few screens and every function on one.

No module over :data:`MODULE_LINES` lines and no function (or method) over
:data:`FUNCTION_LINES` lines, from its ``def`` to its last line, docstring included. A
module may be longer only with a reason: a comment line ``# Longer than 450 lines: ...``
at its top (within its first lines), and its name in :data:`LONG_MODULES`.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[2] / "dualarm_qp"

MODULE_LINES = 450
FUNCTION_LINES = 80

#: The comment that gives a long module's reason, in its first :data:`REASON_WITHIN` lines.
REASON = "# Longer than 450 lines: "
REASON_WITHIN = 5

#: Modules allowed over MODULE_LINES, each with its reason written at its top. Empty: a
#: module that grows past the limit is split by what it holds, or named here with the
#: reason why splitting it would separate one concept (a table of data, say).
LONG_MODULES: frozenset[str] = frozenset()


def _modules() -> list[Path]:
    return sorted(PACKAGE.rglob("*.py"))


def _name(path: Path) -> str:
    return path.relative_to(PACKAGE.parent).as_posix()


def long_functions(source: str, limit: int = FUNCTION_LINES) -> list[tuple[str, int, int]]:
    """Return ``(name, line, length)`` of each function of ``source`` longer than ``limit``."""
    out = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            length = (node.end_lineno or node.lineno) - node.lineno + 1
            if length > limit:
                out.append((node.name, node.lineno, length))
    return out


def has_reason(source: str) -> bool:
    """Whether ``source`` gives the reason it is long, at its top."""
    return any(line.startswith(REASON) and len(line) > len(REASON) + 10
               for line in source.splitlines()[:REASON_WITHIN])


@pytest.mark.parametrize("path", _modules(), ids=_name)
def test_module_is_short_or_says_why(path: Path) -> None:
    source = path.read_text()
    lines = len(source.splitlines())
    name = _name(path)
    if name in LONG_MODULES:
        assert has_reason(source), f"{name} is allowed to be long but gives no reason at its top"
    else:
        assert lines <= MODULE_LINES, (f"{name} has {lines} lines (at most {MODULE_LINES}): "
                                       "split it by what it holds")
        assert not has_reason(source), f"{name} gives a reason to be long: list it in " \
                                       "LONG_MODULES, or drop the reason"


@pytest.mark.parametrize("path", _modules(), ids=_name)
def test_functions_are_short(path: Path) -> None:
    found = long_functions(path.read_text())
    assert not found, f"{_name(path)}: functions over {FUNCTION_LINES} lines: " + ", ".join(
        f"{name} (line {line}, {length} lines)" for name, line, length in found)


def test_the_checks_find_a_long_function_and_a_reason() -> None:
    body = "\n".join(f"    x{i} = {i}" for i in range(FUNCTION_LINES))
    assert long_functions(f"def f():\n{body}\n") == [("f", 1, FUNCTION_LINES + 1)]
    assert long_functions(f"def f():\n{body[:-len(body.splitlines()[-1]) - 1]}\n") == []
    assert has_reason('"""Doc."""\n# Longer than 450 lines: one table of constants.\n')
    assert not has_reason('"""Doc."""\n# Longer than 450 lines: \n')
    for name in LONG_MODULES:
        assert (PACKAGE.parent / name).is_file(), f"LONG_MODULES names {name}, no module"
