"""Every script in examples/ runs as a user would run it, and prints what it promises.

Each runs in a fresh interpreter (the one running the tests), from an empty folder so
that no example depends on the working directory or writes into it.
"""

from __future__ import annotations

import re
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from dualarm_qp.kinematics.robots import example_robots_dir

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def _run(name: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, str(EXAMPLES / name), *ARGS.get(name, [])], cwd=cwd,
                          capture_output=True, text=True, check=False, timeout=120)


def _number(pattern: str, text: str) -> float:
    found = re.search(pattern, text)
    assert found is not None, f"no line matching {pattern!r} in:\n{text}"
    return float(found.group(1))


def _check_own_control_loop(out: str) -> None:
    assert "steps: 500 (" in out
    assert "path time reached: 15.500 of 15.500 s" in out
    assert _number(r"worst closure error: ([\d.]+) mm", out) < 1.0
    # The paper's grasp starts at 450 mm and slides back along the beam.
    assert _number(r"grasp travel: ([\d.]+) mm", out) > 100.0
    assert "0.4500 m ->" in out


def _check_task_in_python(out: str) -> None:
    assert "completed: True" in out
    assert _number(r"worst closure error: ([\d.]+) mm", out) < 1.0
    assert _number(r"worst follower speed ratio: ([\d.]+)", out) <= 1.0 + 1e-6


def _check_urdf_robot_pair(out: str) -> None:
    assert "leader: 6 joints ['shoulder_pan_joint'" in out
    assert "completed: True (301 samples)" in out
    assert _number(r"-> ([\d.]+) m", out) < 0.45  # the follower's grasp slid back


def _check_compare_solvers(out: str) -> None:
    for solver in ("nullspace", "qp:daqp"):
        row = re.search(rf"^{re.escape(solver)}\s+(\w+)\s+([\d.]+)\s+([\d.]+) ms$", out,
                        re.MULTILINE)
        assert row is not None, f"no row for {solver} in:\n{out}"
        assert row.group(1) == "True"
        assert float(row.group(2)) <= 1.0 + 1e-6  # hard limits kept
        assert float(row.group(3)) > 0.0


def _check_custom_limit(out: str) -> None:
    rows = re.findall(r"^(\S+)\s+(completed|FAILED); the tool came within (-?[\d.]+) mm",
                      out, re.MULTILINE)
    solvers = {name for name, _, _ in rows}
    assert {"nullspace", "qp:daqp"} <= solvers, out
    for name, verdict, gap in rows:
        assert verdict == "completed", name
        assert float(gap) >= 0.0, name  # never past the wall
    assert re.search(r"^sns\s+refused: (\S+: )?solver 'sns' takes boxes only, and the limit 'wall' "
                     r"gives rows; solvers that keep rows: nullspace", out, re.MULTILINE), out


def _check_custom_task(out: str) -> None:
    without = _number(r"without the task: completed; the elbow turned at most ([\d.]+) deg", out)
    held = _number(r"with the task: completed; the elbow turned at most ([\d.]+) deg", out)
    assert without > 20.0 and held < 2.0, out


def _check_realtime_loop(out: str) -> None:
    assert "ticks: 1000 (" in out  # --seconds 1
    misses = _number(r"\nmisses: (\d+) ", out)
    assert 0 <= misses <= 1000
    assert "miss rate: " in out and "\nwhy: " in out


CHECKS = {
    "custom_limit.py": _check_custom_limit,
    "custom_task.py": _check_custom_task,
    "own_control_loop.py": _check_own_control_loop,
    "task_in_python.py": _check_task_in_python,
    "urdf_robot_pair.py": _check_urdf_robot_pair,
    "compare_solvers.py": _check_compare_solvers,
    "realtime_loop.py": _check_realtime_loop,
}
NEEDS_ROBOTS = {"urdf_robot_pair.py", "realtime_loop.py"}
#: Command-line arguments of an example (the loop runs 60 s by default).
ARGS = {"realtime_loop.py": ["--seconds", "1"]}


def test_every_example_is_checked_and_none_is_collected_as_a_test():
    names = {p.name for p in EXAMPLES.glob("*.py")}
    assert names == set(CHECKS), "add a check to CHECKS for every example"
    assert not [n for n in names if n.startswith("test_") or n.endswith("_test.py")]


#: Examples that take more than a few seconds (every solver in turn): the full suite only.
SLOW = {"custom_limit.py", "custom_task.py"}


@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.slow) if n in SLOW
                                  else n for n in sorted(CHECKS)])
@pytest.mark.slow
def test_example_runs_and_prints_its_result(name, tmp_path):
    if name in NEEDS_ROBOTS and example_robots_dir() is None:
        pytest.skip("needs the robots extra (example-robot-data)")
    proc = _run(name, tmp_path)
    assert proc.returncode == 0, proc.stderr
    CHECKS[name](proc.stdout)
    assert not list(tmp_path.iterdir()), "an example wrote into the working folder"


def test_urdf_example_without_the_robots_extra_says_what_to_install(tmp_path):
    """With example-robot-data missing the example exits 1 with the pip command."""
    code = textwrap.dedent(f"""
        import runpy
        import dualarm_qp.kinematics.robots as robots
        robots.example_robots_dir = lambda: None  # as if the extra were not installed
        runpy.run_path({str(EXAMPLES / "urdf_robot_pair.py")!r}, run_name="__main__")
    """)
    proc = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True,
                          text=True, check=False, timeout=120)
    assert proc.returncode == 1
    assert proc.stdout == ""
    assert "pip install 'dualarm-qp[robots]'" in proc.stderr
    assert "Traceback" not in proc.stderr
