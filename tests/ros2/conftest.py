"""The ROS 2 environment of the loopback tests, built on first use.

ROS 2's Python packages come from community wheels (``ros-jazzy-*`` on PyPI), which
must not share the project's environment (they re-execute every Python started there).
The tests keep them in ``.venv-ros`` beside ``.venv``: made with the same Python, the
wheels installed with the project's NumPy version, and the project's environment added
after its own packages (a ``.pth`` file), so the node under test imports dualarm_qp and
its compiled kernel from there. It is built once (a lock keeps two test workers from
building it together; about 250 MB from PyPI, a minute or two) and reused while its
stamp matches.

Every test process talks on a ROS domain of its own (claimed by a lock, see
``ros_domain``), on this machine only (``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``).
"""

from __future__ import annotations

import fcntl
import hashlib
import json
import os
import random
import shutil
import subprocess
import sys
import sysconfig
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
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
#: ROS domains the tests may use, 1 to DOMAINS (Fast DDS maps 0 to 101 to ports).
DOMAINS = 101


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


def lock_path() -> Path:
    """The lock every test process of this checkout takes to build ``.venv-ros``.

    Named from a digest of the environment's path, the same in every process (``hash``
    of a string is salted per process: test workers would each take a lock of their own
    and build the environment over each other).
    """
    digest = hashlib.sha256(str(ROS_VENV).encode()).hexdigest()[:16]
    return Path(tempfile.gettempdir()) / f"dualarm_qp-ros-{digest}.lock"


def ros_python() -> Path:
    """Return the ROS environment's Python, building the environment when needed."""
    ROS_VENV.parent.mkdir(parents=True, exist_ok=True)
    with open(lock_path(), "w") as lock:
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


@contextmanager
def ros_domain() -> Iterator[int]:
    """Hold a ROS domain that no other test process on this machine holds.

    Domains 1 to 101 (0 is ROS's default, a user's own graph), tried from a random one
    on; each is claimed by a lock held until the test process ends, so two test workers,
    or two checkouts' test runs at once, never hear each other's topics.
    """
    first = random.SystemRandom().randrange(DOMAINS)
    for k in range(DOMAINS):
        domain = 1 + (first + k) % DOMAINS
        path = Path(tempfile.gettempdir()) / f"dualarm_qp-ros-domain-{domain}.lock"
        with open(path, "w") as lock:
            try:
                fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                continue
            yield domain
            return
    raise RuntimeError(f"every ROS domain 1 to {DOMAINS} is held by another test process")


@pytest.fixture(scope="session")
def ros_env() -> Iterator[RosEnv]:
    python = ros_python()
    env = {k: v for k, v in os.environ.items() if not k.startswith(("ROS_", "RMW_"))}
    with ros_domain() as domain:
        env.update(ROS_DOMAIN_ID=str(domain), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST",
                   RMW_IMPLEMENTATION="rmw_fastrtps_cpp", PYTHONUNBUFFERED="1")
        yield RosEnv(python, env)
