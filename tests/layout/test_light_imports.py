"""The command line's parser, the package and the figure code import nothing heavy.

``dualarm-qp run`` forks its drawing process right after parsing its arguments
(:mod:`dualarm_qp.experiments.figures.process`): that is early only if the parser, and
``import dualarm_qp`` under it, load neither NumPy nor the kinematics and collision
libraries (Pinocchio, Coal), nor the YAML reader or matplotlib. Each check runs in a
fresh interpreter, so that nothing imported by the test session hides an import.
"""

from __future__ import annotations

import subprocess
import sys
import textwrap

import pytest

#: What the parser and the package must not import: each is imported by the functions
#: that run a command, or on first access to a name that needs it.
HEAVY = ("numpy", "pinocchio", "coal", "yaml", "matplotlib")


def imported_after(code: str) -> list[str]:
    """Run ``code`` in a fresh interpreter; return the modules of :data:`HEAVY` it left
    imported."""
    script = textwrap.dedent(code) + textwrap.dedent(f"""
        import sys
        print(" ".join(m for m in {HEAVY!r} if m in sys.modules))
    """)
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          check=False, timeout=120)
    assert proc.returncode == 0, proc.stderr
    return proc.stdout.split()


def test_building_the_parser_imports_nothing_heavy():
    assert imported_after("""
        import dualarm_qp.cli
        dualarm_qp.cli.build_parser()
    """) == []


@pytest.mark.parametrize("argv", [["--help"], ["run", "--help"], ["drive", "--help"],
                                  ["serve", "--help"], ["bag", "--help"]])
def test_the_help_imports_nothing_heavy(argv):
    assert imported_after(f"""
        import contextlib, io
        from dualarm_qp.cli import main
        with contextlib.redirect_stdout(io.StringIO()):
            try:
                main({argv!r})
            except SystemExit:
                pass
    """) == []


@pytest.mark.parametrize("package", ["dualarm_qp", "dualarm_qp.collision", "dualarm_qp.cell",
                                     "dualarm_qp.bag"])
def test_a_package_imports_nothing_heavy_until_a_name_is_used(package):
    assert imported_after(f"import {package}") == []


def test_a_name_loads_on_first_access():
    """The lazy names are the modules' own, and bring their libraries with them."""
    assert imported_after("""
        from dualarm_qp.collision import CLEARANCE_ALLOWANCE, CollisionScene
        from dualarm_qp.collision.scene import CollisionScene as home
        assert CollisionScene is home and CLEARANCE_ALLOWANCE > 0
    """) == ["numpy", "pinocchio", "coal"]


def test_the_figure_code_does_not_import_the_collision_geometry():
    """The clearance figure reads the allowance (:mod:`dualarm_qp.collision.settings`),
    not the scene: the drawing process imports matplotlib, not Pinocchio and Coal."""
    script = textwrap.dedent("""
        import sys
        import dualarm_qp.experiments.figures.process
        import dualarm_qp.experiments.figures.run_figures
        import dualarm_qp.experiments.figures.clearance
        loaded = [m for m in ("dualarm_qp.collision.scene", "dualarm_qp.collision.clearance",
                              "dualarm_qp.kinematics", "pinocchio", "coal") if m in sys.modules]
        print(" ".join(loaded))
    """)
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          check=False, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.split() == []
