"""animation.html in a real, headless Chromium with the network blocked.

Skipped only when no ``chromium`` is installed (CI installs Debian's, see .ci/run); the
page of the UR5 pair, drawn with the arms' meshes, also when example-robot-data is not.
The beam with a pillar beside the follower (a collision scene) shows the obstacle, the
nearest pair and the collision shapes' toggle.
"""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

PIL = pytest.importorskip("PIL.Image", reason="Pillow (a matplotlib dependency) reads PNGs")

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
pytestmark = [pytest.mark.skipif(CHROMIUM is None, reason="chromium is not installed "
                                 "(apt-get install -y chromium; CI installs it)"),
              pytest.mark.slow]  # a browser per test: 5 to 30 s each

WIDTH, HEIGHT = 1280, 800
FLAGS = ["--headless", "--no-sandbox", "--use-gl=angle", "--use-angle=swiftshader",
         "--enable-unsafe-swiftshader", f"--window-size={WIDTH},{HEIGHT}",
         "--virtual-time-budget=8000", "--hide-scrollbars", "--no-first-run",
         "--disable-extensions", "--disable-background-networking",
         "--proxy-server=http://127.0.0.1:9", "--proxy-bypass-list=<-loopback>"]
LEADER, FOLLOWER = (0x3B, 0x6F, 0xB6), (0xC9, 0x83, 0x2F)
#: The obstacle, the nearest pair and the (translucent) collision shapes.
OBSTACLE, NEAREST, SHAPE = (0x8C, 0x56, 0x4B), (0xE6, 0x00, 0x7E), (0x17, 0xBE, 0xCF)


def _chromium(tmp: Path, *args: str) -> str:
    proc = subprocess.run([CHROMIUM, *FLAGS, f"--user-data-dir={tmp / 'profile'}", *args],
                          capture_output=True, text=True, timeout=120, check=False)
    assert proc.returncode == 0, proc.stderr[-2000:]
    return proc.stdout


def _screenshot(tmp: Path, url: str, name: str) -> np.ndarray:
    png = tmp / name
    _chromium(tmp, f"--screenshot={png}", url)
    return np.asarray(PIL.open(png).convert("RGB"), dtype=np.int16)


def _near(img: np.ndarray, rgb: tuple[int, int, int], tol: int = 60) -> np.ndarray:
    return np.abs(img - np.array(rgb)).sum(axis=2) < tol


def _status(dom: str) -> dict[str, str]:
    status = re.search(r'<div id="dualarm-status"[^>]*>', dom)
    assert status, dom[-2000:]
    return dict(re.findall(r'data-([a-z-]+)="([^"]*)"', status.group(0)))


@pytest.fixture(scope="module", params=["run_dir", "ur5_run_dir", "pillar_run_dir"],
                ids=["puma", "ur5_meshes", "puma_pillar"])
def page(request):
    """The PUMA beam (capsules), the UR5 pair (meshes; skipped without the robots), and
    the beam with a pillar (a collision scene)."""
    return (request.getfixturevalue(request.param) / "animation.html").as_uri()


def test_the_page_loads_offline_without_errors_or_requests(page, tmp_path):
    dom = _chromium(tmp_path, "--dump-dom", page + "#t=0.5")
    attrs = _status(dom)
    errors = re.search(r'<pre id="dualarm-errors">(.*?)</pre>', dom, re.S)
    assert attrs.get("ready") == "1", attrs
    assert attrs["errors"] == "0", errors.group(1) if errors else dom[-2000:]
    assert attrs["requests"] == "0", errors.group(1) if errors else ""
    assert int(attrs["frame"]) > 0  # #t= chose a later sample
    assert "grasp" in dom and 'id="r-status">' in dom
    # Joint axes: every one on capsule arms; on mesh arms only those near a limit or
    # outside their range, unless the toggle asks for all.
    shown, flagged, total = (int(v) for v in attrs["axes"].split(","))
    meshes = "ur5run" in page
    assert attrs["all-axes"] == ("0" if meshes else "1")
    assert shown == (flagged if meshes else total) and total == 12


def test_two_timeline_positions_differ_where_the_arms_are(page, tmp_path):
    start = _screenshot(tmp_path, page + "#t=0", "start.png")
    end = _screenshot(tmp_path, page + "#t=100", "end.png")  # past the end: the last sample
    view = slice(0, HEIGHT - 120)  # the 3D pane; the panel with the readout is below
    for img in (start, end):
        pane = img[view]
        assert pane.std() > 10, "blank canvas"
        assert _near(pane, LEADER).sum() > 300 and _near(pane, FOLLOWER).sum() > 300
    arms_start = _near(start[view], LEADER) | _near(start[view], FOLLOWER)
    arms_end = _near(end[view], LEADER) | _near(end[view], FOLLOWER)
    moved = arms_start ^ arms_end
    assert moved.sum() > 200, "the arms did not move between the two positions"
    changed = np.abs(start[view] - end[view]).sum(axis=2) > 30
    assert (changed & moved).sum() > 0.5 * moved.sum()
    if "ur5run" not in page:  # the beam has no obstacle; with its pillar, one and a pair
        pillar = "pillarrun" in page
        assert (_near(start[view], OBSTACLE).sum() > 1000) == pillar
        assert (_near(start[view], NEAREST).sum() > 15) == pillar


@pytest.fixture(scope="module")
def pillar_page(pillar_run_dir):
    return (pillar_run_dir / "animation.html").as_uri()


def test_the_obstacle_and_the_nearest_pair_are_drawn_and_the_shapes_toggle(pillar_page,
                                                                            tmp_path):
    """At t = 0.5 s the follower's link1 is 42 mm from the pillar (d_i = 100 mm)."""
    off = _status(_chromium(tmp_path, "--dump-dom", pillar_page + "#t=0.5"))
    assert off["ready"] == "1" and off["errors"] == "0"
    assert off["obstacles"] == "1"
    assert re.fullmatch(r"follower\.link1 - pillar: 4\d\.\d mm", off["near"]), off["near"]
    shown, total = (int(v) for v in off["shapes"].split(","))
    assert off["shapes-on"] == "0" and shown == 0 and total >= 10  # off by default
    dom = _chromium(tmp_path, "--dump-dom", pillar_page + "#t=0.5&shapes=1")
    on = _status(dom)  # the address option clicks the checkbox, as a person would
    assert on["shapes-on"] == "1" and on["shapes"] == f"{total},{total}"
    assert re.search(r'<div id="near-label"[^>]*>follower\.link1 - pillar: 4\d', dom)
    assert 'id="r-clearance">follower.link1 - pillar' in dom

    view = slice(0, HEIGHT - 140)  # the 3D pane; the panel (four rows) is below
    plain = _screenshot(tmp_path, pillar_page + "#t=0.5", "off.png")[view]
    shapes = _screenshot(tmp_path, pillar_page + "#t=0.5&shapes=1", "on.png")[view]
    for img in (plain, shapes):
        assert _near(img, OBSTACLE).sum() > 1000, "no obstacle drawn"
        assert _near(img, NEAREST).sum() > 15, "no nearest-pair segment"
    assert _near(plain, SHAPE, 90).sum() < 50 < 2000 < _near(shapes, SHAPE, 90).sum()
    assert (np.abs(plain - shapes).sum(axis=2) > 30).sum() > 5000  # the toggle shows them
