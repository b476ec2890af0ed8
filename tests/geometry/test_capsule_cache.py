"""Fitted capsules are kept on disk: a second process reads them instead of fitting,
a changed robot description or a damaged file is fitted again, and writers racing on one
folder leave one whole file."""

from __future__ import annotations

import threading
from pathlib import Path

import numpy as np
import pytest

from dualarm_qp.geometry import capsule_cache, links, urdf_capsules

ARM = """<?xml version="1.0"?>
<robot name="two_link">
  <link name="base">
    <collision><geometry><box size="0.2 0.2 0.1"/></geometry></collision>
  </link>
  <link name="upper">
    <collision><origin xyz="0.25 0 0" rpy="0 1.5707963 0"/>
      <geometry><cylinder radius="{radius}" length="0.5"/></geometry></collision>
  </link>
  <link name="fore">
    <collision><origin xyz="0.15 0 0"/><geometry><box size="0.3 0.06 0.06"/></geometry>
    </collision>
  </link>
  <link name="tip"/>
  <joint name="shoulder" type="revolute">
    <parent link="base"/><child link="upper"/><origin xyz="0 0 0.1"/><axis xyz="0 0 1"/>
    <limit lower="-2" upper="2" velocity="1" effort="1"/>
  </joint>
  <joint name="elbow" type="revolute">
    <parent link="upper"/><child link="fore"/><origin xyz="0.5 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-2" upper="2" velocity="1" effort="1"/>
  </joint>
  <joint name="flange" type="fixed">
    <parent link="fore"/><child link="tip"/><origin xyz="0.3 0 0"/>
  </joint>
</robot>
"""


@pytest.fixture
def cache(tmp_path, monkeypatch):
    """An empty cache folder, and a process that has fitted nothing yet."""
    folder = tmp_path / "cache"
    monkeypatch.setenv(capsule_cache.CACHE_ENV, str(folder))
    monkeypatch.setattr(links, "_FITTED", {})
    return folder


@pytest.fixture
def fits(monkeypatch):
    """Count the capsules fitted (each call of fit_capsule)."""
    calls = []
    fit = capsule_cache.fit.fit_capsule

    def counted(points, radii=None):
        calls.append(len(points))
        return fit(points, radii)

    monkeypatch.setattr(capsule_cache.fit, "fit_capsule", counted)
    return calls


def write_arm(folder: Path, radius: float = 0.05) -> Path:
    path = folder / "two_link.urdf"
    path.write_text(ARM.format(radius=radius))
    return path


def new_process() -> None:
    """Forget what this process fitted, as a new process would not know it."""
    links._FITTED.clear()


def same(a, b) -> bool:
    return sorted(a) == sorted(b) and all(
        np.array_equal(a[k].a, b[k].a) and np.array_equal(a[k].b, b[k].b)
        and a[k].radius == b[k].radius for k in a)


def test_a_second_process_reads_the_capsules_instead_of_fitting(cache, fits, tmp_path,
                                                                monkeypatch):
    urdf = write_arm(tmp_path)
    first = urdf_capsules(urdf, "base", "tip")
    assert sorted(first) == [0, 1, 2] and len(fits) == 3
    assert len(list((cache / "capsules").glob("*.json"))) == 1
    new_process()

    def no_fit(points, radii=None):
        raise AssertionError("fitted again")

    monkeypatch.setattr(capsule_cache.fit, "fit_capsule", no_fit)
    again = urdf_capsules(urdf, "base", "tip")
    assert same(again, first)  # bit for bit: floats are kept by repr
    # The same robot from another file (a copy elsewhere) is the same description.
    copy = tmp_path / "copy"
    copy.mkdir()
    assert same(urdf_capsules(write_arm(copy), "base", "tip"), first)


def test_a_changed_description_is_fitted_again(cache, fits, tmp_path):
    first = urdf_capsules(write_arm(tmp_path), "base", "tip")
    new_process()
    wider = urdf_capsules(write_arm(tmp_path, radius=0.08), "base", "tip")
    assert len(fits) == 6
    assert wider[1].radius > first[1].radius + 0.02
    assert wider[2].radius == first[2].radius  # the forearm did not change
    assert len(list((cache / "capsules").glob("*.json"))) == 2


ROD = {1: [(np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.4]]), np.full(2, 0.05))],
       2: [(np.array([[0.1, 0.0, 0.0]]), np.array([0.02]))]}


@pytest.mark.parametrize("damage", ["", "{not json", '{"capsules": []}',
                                    '{"capsules": {"1": {"a": [0, 0]}, "2": {}}}',
                                    '{"capsules": {"1": {"a": [0, 0, 0], "b": [0, 0, 1], '
                                    '"radius": -1}, "2": {}}}'])
def test_a_damaged_file_is_fitted_again_and_replaced(cache, fits, damage):
    first = capsule_cache.cached_fit(ROD)
    (stored,) = (cache / "capsules").glob("*.json")
    stored.write_text(damage)
    assert same(capsule_cache.cached_fit(ROD), first)
    assert len(fits) == 4
    assert same(capsule_cache._load(stored, [1, 2]), first)


def test_a_folder_that_cannot_be_written_only_means_no_cache(tmp_path, monkeypatch, fits):
    blocker = tmp_path / "file"
    blocker.write_text("a file where the folder would be")
    monkeypatch.setenv(capsule_cache.CACHE_ENV, str(blocker / "cache"))
    monkeypatch.setattr(links, "_FITTED", {})
    urdf = write_arm(tmp_path)
    first = urdf_capsules(urdf, "base", "tip")
    new_process()
    assert same(urdf_capsules(urdf, "base", "tip"), first) and len(fits) == 6


def test_the_cache_folder(monkeypatch, tmp_path):
    monkeypatch.setenv(capsule_cache.CACHE_ENV, str(tmp_path / "mine"))
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert capsule_cache.cache_dir() == tmp_path / "mine"
    monkeypatch.delenv(capsule_cache.CACHE_ENV)
    assert capsule_cache.cache_dir() == tmp_path / "xdg" / "dualarm_qp"
    monkeypatch.setenv("XDG_CACHE_HOME", "")
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert capsule_cache.cache_dir() == tmp_path / "home" / ".cache" / "dualarm_qp"


def test_the_key_is_the_geometry_and_the_fit(monkeypatch, tmp_path):
    balls = {1: [(np.zeros((2, 3)), np.ones(2))], 2: [(np.eye(3), np.zeros(3))]}
    key = capsule_cache.balls_digest(balls)
    assert capsule_cache.balls_digest({2: balls[2], 1: balls[1]}) == key  # key order
    moved = {1: [(np.full((2, 3), 1e-12), np.ones(2))], 2: balls[2]}
    assert capsule_cache.balls_digest(moved) != key
    swapped = {1: balls[2], 2: balls[1]}
    assert capsule_cache.balls_digest(swapped) != key
    # another fit (its source changed) is another key
    source = tmp_path / "fit.py"
    source.write_text(Path(capsule_cache.fit.__file__).read_text() + "\n# changed\n")
    monkeypatch.setattr(capsule_cache.fit, "__file__", str(source))
    assert capsule_cache.balls_digest(balls) != key


def test_writers_racing_on_one_folder_leave_one_whole_file(cache):
    capsules = capsule_cache.cached_fit(ROD)
    (path,) = (cache / "capsules").glob("*.json")
    seen: list[object] = []
    stop = threading.Event()

    def write() -> None:
        for _ in range(40):
            capsule_cache._store(path, capsules)

    def read() -> None:
        while not stop.is_set():
            seen.append(capsule_cache._load(path, [1, 2]))

    reader = threading.Thread(target=read)
    reader.start()
    writers = [threading.Thread(target=write) for _ in range(4)]
    for w in writers:
        w.start()
    for w in writers:
        w.join()
    stop.set()
    reader.join()
    assert seen and all(found is not None and same(found, capsules) for found in seen)
    assert [p.name for p in path.parent.iterdir()] == [path.name]  # no temporary left
