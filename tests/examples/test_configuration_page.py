"""docs/configuration.md's frames and ``near`` sections say what the library does.

The ``near`` snippet runs and prints what the page shows, and the loader solves the same
start from the same seed; the ``H1`` table's constructions give the files' ``H1``; the
follower's tool axes are the surface's ``s*`` and ``a*``; the picture is there.
"""

from __future__ import annotations

import copy
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

import dualarm_qp as dq
from dualarm_qp.experiments.config import parse_config
from dualarm_qp.kinematics.robots import example_robots_dir

ROOT = Path(__file__).resolve().parents[2]
PAGE = ROOT / "docs" / "configuration.md"
MM_DEG = {"length": "mm", "angle": "deg"}
needs_robots = pytest.mark.skipif(example_robots_dir() is None,
                                  reason="needs the robots extra (example-robot-data)")


def _file(name: str) -> dict:
    return yaml.safe_load((ROOT / "configs" / name).read_text())


def _H1(name: str) -> np.ndarray:
    """The file's H1 [m], read as the file is read."""
    data = _file(name)
    units = {k: v for k, v in data["units"].items() if k in ("length", "angle")}
    return dq.pose(**data["object"]["H1"], units=units)


def _section(title: str) -> str:
    text = PAGE.read_text()
    start = text.index(title)
    end = text.find("\n## ", start + len(title))
    return text[start:] if end < 0 else text[start:end]


@needs_robots
def test_the_near_snippet_prints_what_the_page_shows(tmp_path):
    section = _section("### Choosing `near` joints")
    (code,) = re.findall(r"```python\n(.*?)```", section, re.DOTALL)
    (shown,) = re.findall(r"```text\n(.*?)```", section, re.DOTALL)
    proc = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True,
                          text=True, check=False, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout == shown


@needs_robots
def test_the_loader_solves_the_same_start_from_the_same_seed():
    """The snippet's first seed, written as the UR5 file's leader ``near``."""
    data = copy.deepcopy(_file("ur5_pair_sliding_bar.yaml"))
    data["leader"]["initial"] = {"near": [0, -90, 90, -90, -90, -90]}
    exp = dq.build_experiment(parse_config(data))
    ur5 = dq.example_robot_arm("ur5", "base_link", "tool0")
    target = (dq.pose([400, 0, 300], rpy=[0, 90, 0], units=MM_DEG)
              @ np.linalg.inv(_H1("ur5_pair_sliding_bar.yaml")))
    found = dq.ik_dls(ur5, target, np.radians([0, -90, 90, -90, -90, -90]),
                      respect_limits=False)
    np.testing.assert_allclose(exp.initial.q_l, found.q, rtol=0, atol=1e-8)
    np.testing.assert_allclose(exp.notes["leader_q0_deg"], np.degrees(found.q), atol=1e-5)


def test_the_h1_table_constructions_give_the_files_h1():
    bar = dq.PlaneBar()  # every pattern's surface: face x = 0, sliding along +z
    R2 = bar.frame(0.0)
    turn = dq.pose(rpy=[0, 0, np.pi])  # half a turn about the tool's z axis
    np.testing.assert_allclose(_H1("puma_beam_limits.yaml"), np.eye(4), atol=1e-15)
    np.testing.assert_allclose(_H1("ur5_pair_sliding_bar.yaml"),
                               np.linalg.inv(bar.pose(0.0)), atol=1e-15)
    np.testing.assert_allclose(_H1("panda_pair.yaml"),
                               np.linalg.inv(bar.pose(0.6) @ turn), atol=1e-15)
    # Baxter: the same axes, the leader at the middle of the opposite rim (y = -500 mm).
    T_object_leader = dq.pose([0, -0.5, 0.25], rotation=R2)
    np.testing.assert_allclose(_H1("baxter_tray.yaml"), np.linalg.inv(T_object_leader),
                               atol=1e-15)


def test_the_follower_tool_is_z_along_a_star_and_x_along_s_star():
    """The PUMA beam at t0: the follower's tool axes in the world are R_object a*, s*."""
    exp = dq.build_experiment(dq.load_config(ROOT / "configs" / "puma_beam_limits.yaml"))
    task = exp.task
    T_f = task.follower.fk(exp.initial.q_f)
    R_o = task.trajectory.pose(task.trajectory.t0)[:3, :3]
    sigma = exp.initial.sigma
    np.testing.assert_allclose(T_f[:3, 2], R_o @ task.surface.normal(sigma), atol=1e-6)
    np.testing.assert_allclose(T_f[:3, 0], R_o @ task.surface.tangent(sigma), atol=1e-6)
    # H1 is the identity here: the follower's tool z is the leader's tool x.
    T_l = task.leader.fk(exp.initial.q_l)
    np.testing.assert_allclose(T_f[:3, 2], T_l[:3, 0], atol=1e-6)


@pytest.mark.slow
def test_the_frames_picture_is_referenced_and_there(tmp_path):
    links = re.findall(r"\]\((figures/[^)]+\.png)\)", PAGE.read_text())
    assert "figures/grasp_frames.png" in links
    for link in links:
        path = PAGE.parent / link
        assert path.is_file(), link
        assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # Its script still draws it.
    out = tmp_path / "grasp_frames.png"
    proc = subprocess.run([sys.executable, str(ROOT / "docs" / "figures" / "grasp_frames.py"),
                           str(out)], cwd=tmp_path, capture_output=True, text=True,
                          check=False, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
