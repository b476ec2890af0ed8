"""The README's two set-up commands compile the kernel once between them.

Both install with ``--no-build-isolation`` after ``pip install -r
requirements-build.txt``: the build then runs in the project's own ``.venv``, whose
paths do not change between the two commands, so CMake's build folder (``build/``)
stays valid and the second install reuses the first one's compiled kernel. That holds
only while ``requirements-build.txt`` lists what ``pyproject.toml`` builds with.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

try:
    import tomllib
except ImportError:  # Python 3.10
    tomllib = pytest.importorskip("tomli")


def _requirements() -> list[str]:
    lines = (ROOT / "requirements-build.txt").read_text().splitlines()
    return [line.strip() for line in lines if line.strip() and not line.startswith("#")]


def _readme_commands() -> list[str]:
    text = (ROOT / "README.md").read_text()
    blocks = re.findall(r"```bash\n(.*?)```", text, flags=re.S)
    return [line for block in blocks for line in block.splitlines()
            if line.startswith("python3 -m venv .venv")]


def test_build_requirements_are_pyprojects():
    requires = tomllib.loads((ROOT / "pyproject.toml").read_text())["build-system"]["requires"]
    listed = _requirements()
    assert sorted(requires) == sorted(r for r in listed if r != "ninja")
    assert "ninja" in listed


def test_both_set_up_commands_build_in_the_venv():
    commands = _readme_commands()
    assert len(commands) == 2  # the main job and the tests
    for command in commands:
        assert ".venv/bin/pip install -r requirements-build.txt && " in command
        assert ".venv/bin/pip install --no-build-isolation -e " in command
