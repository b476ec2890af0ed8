"""The ROS 2 environment of the loopback tests, built on first use.

ROS 2's Python packages come from community wheels (``ros-jazzy-*`` on PyPI), which
must not share the project's environment (they re-execute every Python started there).
The tests keep them in ``.venv-ros`` beside ``.venv``: made with the same Python, the
wheels installed with the project's NumPy version, and the project's environment added
after its own packages (a ``.pth`` file), so the node under test imports dualarm_qp and
its compiled kernel from there. It is built once (a lock keeps two test workers from
building it together; about 250 MB from PyPI, a minute or two) and reused while its
stamp matches.

Every test session talks on a ROS domain of its own, on this machine only
(``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``).
"""

from __future__ import annotations

import fcntl
import json
import os
import random
import shutil
import subprocess
import sys
import sysconfig
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
ROS_VENV = ROOT / ".venv-ros"
ROS_PACKAGES = ("ros-jazzy-rclpy", "ros-jazzy-rmw-fastrtps-cpp", "ros-jazzy-sensor-msgs",
                "ros-jazzy-std-msgs", "ros-jazzy-trajectory-msgs", "ros-jazzy-diagnostic-msgs",
                "ros-jazzy-geometry-msgs", "ros-jazzy-rosgraph-msgs")
STAND_IN = Path(__file__).resolve().parent / "standin.py"


def _stamp() -> dict[str, object]:
    return {"packages": list(ROS_PACKAGES), "numpy": np.__version__,
            "project": sysconfig.get_paths()["purelib"], "python": sys.version}


def _python() -> Path:
    return ROS_VENV / "bin" / "python"


def _usable() -> bool:
    stamp = ROS_VENV / "dualarm_qp-stamp.json"
    if not (_python().is_file() and stamp.is_file()):
        return False
    if json.loads(stamp.read_text()) != _stamp():
        return False
    probe = subprocess.run([str(_python()), "-c", "import rclpy, dualarm_qp"],
                           capture_output=True, text=True, timeout=300, check=False)
    return probe.returncode == 0


def _build() -> None:
    shutil.rmtree(ROS_VENV, ignore_errors=True)
    base = getattr(sys, "_base_executable", sys.executable)
    subprocess.run([base, "-m", "venv", str(ROS_VENV)], check=True, timeout=300)
    pip = [str(_python()), "-m", "pip", "install", "-q", "--disable-pip-version-check"]
    done = subprocess.run([*pip, *ROS_PACKAGES, f"numpy=={np.__version__}"],
                          capture_output=True, text=True, timeout=1800, check=False)
    if done.returncode != 0:
        raise RuntimeError(f"installing ROS 2's wheels into {ROS_VENV} failed (PyPI is needed "
                           f"once):\n{done.stderr[-3000:]}")
    site = Path(subprocess.run([str(_python()), "-c",
                                "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                               capture_output=True, text=True, check=True).stdout.strip())
    project = sysconfig.get_paths()["purelib"]
    (site / "zz_dualarm_qp_project.pth").write_text(
        f"import site; site.addsitedir({project!r})\n")
    (ROS_VENV / "dualarm_qp-stamp.json").write_text(json.dumps(_stamp()))


def ros_python() -> Path:
    """Return the ROS environment's Python, building the environment when needed."""
    ROS_VENV.parent.mkdir(parents=True, exist_ok=True)
    lock_path = Path(tempfile.gettempdir()) / f"dualarm_qp-{abs(hash(str(ROS_VENV)))}.lock"
    with open(lock_path, "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not _usable():
            _build()
            if not _usable():
                raise RuntimeError(f"{ROS_VENV} was built but cannot import rclpy and "
                                   "dualarm_qp")
    return _python()


@dataclass(frozen=True)
class RosEnv:
    """How to start a process in the tests' ROS 2 graph."""

    python: Path
    env: dict[str, str]

    def popen(self, args: list[str], **kw) -> subprocess.Popen:
        return subprocess.Popen([str(self.python), *args], env=self.env, cwd=ROOT, **kw)


@pytest.fixture(scope="session")
def ros_env() -> RosEnv:
    python = ros_python()
    env = {k: v for k, v in os.environ.items() if not k.startswith(("ROS_", "RMW_"))}
    env.update(ROS_DOMAIN_ID=str(random.SystemRandom().randrange(1, 100)),
               ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST", RMW_IMPLEMENTATION="rmw_fastrtps_cpp",
               PYTHONUNBUFFERED="1")
    return RosEnv(python, env)
