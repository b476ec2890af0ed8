"""``dualarm-qp collisions``: a file with a collision scene run with collision avoidance,
without it, and with the fixed grasp, and the figure of their clearances.

The whole pillar story (penetration without avoidance) is checked by the slow test of
``test_pillar.py``; here a short run of the same file checks what the command writes,
how it replaces its own earlier output, and what it refuses.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import yaml
from sigint import child_default_sigint

from dualarm_qp.cli import main
from dualarm_qp.experiments import build_experiment, load_config
from dualarm_qp.experiments.figures import Curve, avoidance_figure
from dualarm_qp.experiments.figures.avoidance import near_window

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
PILLAR = CONFIGS / "puma_beam_pillar.yaml"
FOLDERS = ("avoiding", "not_avoiding", "fixed_grasp")


def _pillar(tmp_path: Path, name: str = "pillar.yaml", **controller) -> Path:
    d = yaml.safe_load(PILLAR.read_text())
    d["controller"].update(controller)
    path = tmp_path / name
    path.write_text(yaml.safe_dump(d))
    return path


@pytest.fixture(scope="module")
def compared(tmp_path_factory):
    """A comparison of the pillar file cut to 0.62 s (20 samples)."""
    tmp = tmp_path_factory.mktemp("cmp")
    config = _pillar(tmp, duration=0.62)
    out = tmp / "out"
    code = main(["collisions", str(config), "--out", str(out), "--quiet", "--no-plots"])
    return config, out, code


def test_the_comparison_writes_three_runs_a_figure_and_a_record(compared):
    _, out, code = compared
    assert code == 0
    entries = {p.name + ("/" if p.is_dir() else "") for p in out.iterdir()}
    assert entries == {"collisions.json", "collisions.png", *(f"{f}/" for f in FOLDERS)}
    record = json.loads((out / "collisions.json").read_text())
    assert set(record["outputs"]) == entries - {"collisions.json"}
    assert record["status"] == "completed" and record["figures"] == ["collisions.png"]
    assert record["collision"]["safety_distance_m"] == pytest.approx(0.02)
    runs = record["runs"]
    assert [runs[f]["solver"] for f in FOLDERS] == ["nullspace", "nullspace", "fixed_grasp"]
    assert [runs[f]["collision_avoidance"] for f in FOLDERS] == [True, False, False]
    for f in FOLDERS:
        s = json.loads((out / f / "summary.json").read_text())
        assert s["samples"] == runs[f]["samples"] == 21 and s["solver"] == runs[f]["solver"]
        assert runs[f]["clearance_min_m"] == s["realised_limits"]["clearance"]["min_m"]
        assert "joints.png" not in s["outputs"]  # --no-plots: the runs' own figures
    # 0.6 s into the path the pillar is far: nothing penetrates yet.
    assert record["claims"] == {"avoiding_completes_and_keeps_clearance": True,
                                "not_avoiding_penetrates": False,
                                "fixed_grasp_penetrates": False}


def test_each_runs_config_yaml_rebuilds_that_run(compared):
    _, out, _ = compared
    for folder, solver, enabled in zip(FOLDERS, ("nullspace", "nullspace", "fixed_grasp"),
                                       (True, False, False), strict=True):
        path = out / folder / "config.yaml"
        assert f"as '{folder}'" in path.read_text()
        exp = build_experiment(load_config(path), str(path))
        assert exp.solver_name == solver and exp.task.scene.settings.enabled is enabled


@pytest.mark.slow
def test_a_comparison_replaces_its_own_output_and_keeps_other_files(compared, tmp_path):
    config, _, _ = compared
    out = tmp_path / "out"
    argv = ["collisions", str(config), "--out", str(out), "--quiet", "--no-plots"]
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    assert main(argv) == 2  # a folder in use, not by a comparison
    assert main([*argv, "--force"]) == 0
    (out / "avoiding" / "mine.txt").write_text("mine")
    before = (out / "collisions.json").stat().st_mtime_ns
    assert main(argv) == 0  # its own earlier output is replaced without --force
    assert (out / "collisions.json").stat().st_mtime_ns > before
    assert (out / "notes.txt").read_text() == (out / "avoiding" / "mine.txt").read_text()
    assert set(json.loads((out / "collisions.json").read_text())["outputs"]) == {
        "collisions.png", *(f"{f}/" for f in FOLDERS)}


def _no_geometry(d: dict) -> None:
    del d["scene"], d["object"]["shape"], d["collision"]


def _sns(d: dict) -> None:
    d["solver"]["name"] = "sns"  # takes no rows: cannot avoid collisions


@pytest.mark.parametrize(("change", "says"), [
    (_no_geometry, "key 'scene': the file gives no collision scene"),
    (_sns, "sns"),
])
def test_a_file_without_a_scene_or_without_rows_is_bad_input(tmp_path, capsys, change, says):
    d = yaml.safe_load(PILLAR.read_text())
    change(d)
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(d))
    out = tmp_path / "out"
    assert main(["collisions", str(path), "--out", str(out), "--quiet"]) == 2
    assert says in capsys.readouterr().err
    assert not out.exists()  # refused before anything was written


def _curve(label, t, value, colour="C0"):
    return Curve(label, np.asarray(t, float), np.asarray(value, float), colour)


def test_the_avoidance_figure_draws_the_distances_and_zooms_where_runs_come_near():
    t = np.linspace(0.0, 10.0, 101)
    near = _curve("near", t, np.maximum(0.5 - 0.05 * t, 0.02))   # within d_i from t = 8
    into = _curve("into", t, 0.5 - 0.06 * t, "C1")                # within d_i from 6.67
    grasp = [_curve("near", t, 0.45 - 0.01 * t), _curve("into", t, np.full(101, 0.45), "C1")]
    fig = avoidance_figure([near, into], grasp, safety_distance=0.02,
                           influence_distance=0.1, grasp_range=(0.0, 0.4), scale=1e3,
                           unit="mm", title="test")
    clear, grasp_ax, zoom, _ = fig.axes[:4]

    def levels(ax, gid):
        return sorted(line.get_ydata()[0] for line in ax.get_lines() if line.get_gid() == gid)

    assert levels(clear, "limit:safety_distance") == [20.0]
    assert levels(clear, "limit:influence_distance") == [100.0]
    assert levels(clear, "contact") == [0.0]
    assert levels(grasp_ax, "limit:grasp_range") == [0.0, 400.0]
    band = [p for p in clear.patches if p.get_gid() == "penetration"]
    assert len(band) == 1 and band[0].get_extents().ymax > 0  # drawn up to 0
    lo, hi = clear.get_ylim()
    assert lo < -100.0 < hi  # the deepest value shown (into: -0.1 m at t = 10 s)
    assert hi <= (0.02 + 2.5 * 0.08) * 1e3 * 1.1  # far values cut: they give no row
    window = near_window([near, into], 0.1)
    assert window is not None and window[0] < 20 / 3 < window[1] == 10.0
    assert zoom.get_xlim() == pytest.approx(window)
    assert "axes stop at 220 mm" in "".join(text.get_text() for text in fig.texts)
    legend = [text.get_text() for text in fig.legends[0].get_texts()]
    assert legend[:2] == ["near", "into"] and "safety distance d_s = 20 mm" in legend


def test_no_zoom_when_no_run_comes_within_the_influence_distance():
    t = np.linspace(0.0, 1.0, 11)
    far = _curve("far", t, np.full(11, 0.15))
    fig = avoidance_figure([far], [_curve("far", t, np.full(11, 0.3))],
                           safety_distance=0.02, influence_distance=0.1,
                           grasp_range=(0.0, 0.4), scale=1e3, unit="mm", title="far")
    assert near_window([far], 0.1) is None and len(fig.axes) == 2


@pytest.mark.slow
@pytest.mark.sigint
@pytest.mark.skipif(os.name != "posix", reason="POSIX signals")
def test_an_interrupt_in_the_second_run_records_what_was_done(tmp_path):
    """SIGINT while the second run rolls out: exit 130, the first run whole, the second
    written as interrupted, no figure, collisions.json saying so."""
    # 12,000 samples a run: the second run's rollout must outlast the wait below by far
    # (at 1,500 and then at 3,000 samples a faster step let it finish first, and the
    # signal then came while its outputs were written, which discards them). The second
    # run has no collision rows: about 1 s of rollout at 80 us a step.
    config = _pillar(tmp_path, duration=6.0, dt=0.0005, correction_gain=250,
                     leader_gain=250)
    out = tmp_path / "out"
    proc = subprocess.Popen([sys.executable, "-m", "dualarm_qp.cli", "collisions", str(config),
                             "--out", str(out), "--quiet", "--no-plots"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                            preexec_fn=child_default_sigint)
    try:
        deadline = time.monotonic() + 120
        first = out / "avoiding" / "summary.json"
        while not first.exists() and proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.005)
        time.sleep(0.15)
        assert proc.poll() is None, "the second run ended before the signal"
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == 130, err
    assert "Traceback" not in err
    record = json.loads((out / "collisions.json").read_text())
    assert record["status"] == "interrupted" and record["interrupted_run"] == "not_avoiding"
    assert record["figures"] == [] and record["claims"] == {}
    assert record["outputs"] == ["avoiding/", "not_avoiding/"]
    assert not (out / "collisions.png").exists() and not (out / "fixed_grasp").exists()
    statuses = [json.loads((out / f / "summary.json").read_text())["status"]
                for f in ("avoiding", "not_avoiding")]
    assert statuses == ["completed", "interrupted"]
