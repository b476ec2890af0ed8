"""``dualarm-qp collisions``: a file with a collision scene run with collision avoidance,
without it, and with the fixed grasp, and the figure of their clearances.

The whole pillar story (penetration without avoidance) is checked by the slow test of
``test_pillar.py``; here a short run of the same file checks what the command writes,
how it replaces its own earlier output, and what it refuses.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
import yaml
from sigint import child_default_sigint

from dualarm_qp.cli import main
from dualarm_qp.experiments import build_experiment, load_config
from dualarm_qp.experiments.avoidance import Comparison, _checks, describe
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
    """A comparison of the pillar file cut to 0.62 s (20 samples): the pillar is still
    far, so nothing penetrates, as in a file of your own with no demo story."""
    tmp = tmp_path_factory.mktemp("cmp")
    config = _pillar(tmp, duration=0.62)
    out = tmp / "out"
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        code = main(["collisions", str(config), "--out", str(out), "--quiet", "--no-plots"])
    return config, out, code, printed.getvalue()


def test_the_comparison_writes_three_runs_a_figure_and_a_record(compared):
    _, out, code, _ = compared
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
    # 0.6 s into the path the pillar is far: nothing penetrates yet. That is measured;
    # the one claim made of any file is the avoiding run's.
    assert record["claims"] == {"avoiding_completes_and_keeps_clearance": True}
    assert [runs[f]["penetration"] for f in FOLDERS] == [False, False, False]
    assert [runs[f]["failure"] for f in FOLDERS] == [None, None, None]


def test_a_file_without_the_demos_story_prints_what_was_measured_and_no_NO(compared):
    """Nothing penetrates without avoidance: measured and printed, not a failed claim."""
    _, _, code, printed = compared
    assert code == 0
    assert "NO" not in printed and "penetrates" not in printed
    lines = printed.splitlines()
    for folder in FOLDERS:
        line = next(x for x in lines if x.startswith(f"  {folder} "))
        assert "21 samples, completed; nearest " in line and "; no penetration; " in line
    assert "  yes  the run with avoidance completes and keeps the safety distance" in lines


def _crate(tmp_path: Path) -> Path:
    """The pillar file, cut to 0.31 s (10 mm of travel), with a crate 5 mm beside the
    beam, across its path."""
    d = yaml.safe_load(_pillar(tmp_path, duration=0.31).read_text())
    d["scene"]["obstacles"].append({"name": "crate", "box": {"size": [30, 40, 30]},
                                    "pose": {"position": [40, 900, 260]}})
    path = tmp_path / "crate.yaml"
    path.write_text(yaml.safe_dump(d))
    return path


@pytest.mark.slow
def test_only_a_failed_claim_fails_the_comparison(tmp_path, capsys):
    """The crate is 5 mm from the object at the start, within d_s: the avoiding run is
    refused before its first sample (exit 1, NO); the runs without avoidance complete
    and go into it (measured: penetration)."""
    out = tmp_path / "out"
    assert main(["collisions", str(_crate(tmp_path)), "--out", str(out), "--quiet",
                 "--no-plots"]) == 1
    captured = capsys.readouterr()
    lines = captured.out.splitlines()
    avoiding = next(x for x in lines if x.startswith("  avoiding "))
    assert "0 samples, FAILED on collision at t = 0 s" in avoiding
    assert any("object - crate is 5.30 mm apart at the start" in x for x in lines)  # below it
    for folder in ("not_avoiding", "fixed_grasp"):
        line = next(x for x in lines if x.startswith(f"  {folder} "))
        assert "completed; nearest -" in line and "(object - crate); penetration;" in line
    assert "  NO   the run with avoidance completes and keeps the safety distance" in lines
    assert "claim not met: the run with avoidance completes" in captured.err
    record = json.loads((out / "collisions.json").read_text())
    assert record["status"] == "failed"
    assert record["claims"] == {"avoiding_completes_and_keeps_clearance": False}
    assert record["runs"]["avoiding"]["failure"]["criterion"] == "collision"
    assert record["runs"]["not_avoiding"]["penetration"] is True


@pytest.mark.slow
def test_the_demos_story_is_claimed_only_on_request(compared, tmp_path, capsys):
    """--expect-penetration claims the pillar demo's story: on the short file nothing
    penetrates yet, so those claims fail (exit 1)."""
    config, _, _, _ = compared
    out = tmp_path / "out"
    assert main(["collisions", str(config), "--out", str(out), "--quiet", "--no-plots",
                 "--expect-penetration"]) == 1
    lines = capsys.readouterr().out.splitlines()
    assert "  yes  the run with avoidance completes and keeps the safety distance" in lines
    assert "  NO   the run without avoidance penetrates" in lines
    assert "  NO   the fixed grasp penetrates" in lines
    record = json.loads((out / "collisions.json").read_text())
    assert record["claims"] == {"avoiding_completes_and_keeps_clearance": True,
                                "not_avoiding_penetrates": False,
                                "fixed_grasp_penetrates": False}


def test_a_run_without_avoidance_that_fails_is_a_measurement_with_its_reason():
    """The fixed grasp cannot do the task of a file: printed with why; the claim holds."""
    failure = {"criterion": "range", "sample": 40, "t_s": 1.24,
               "message": "step 40 at t = 1.2400 s: follower joint 3 left its range"}

    def outcome(ok, solver, **extra):
        summary = {"solver": solver, "status": "completed" if ok else "failed",
                   "samples": 41 if not ok else 101, "grasp_start_m": 0.45,
                   "grasp_end_m": 0.3, "failure": None if ok else failure,
                   "realised_limits": {"clearance": {
                       "min_m": 0.05, "pair": "follower.link2 - pillar", "sample": 3,
                       "kept": True, "enforced": solver == "nullspace" and ok, **extra}}}
        return SimpleNamespace(ok=ok, summary=summary)

    runs = {"avoiding": outcome(True, "nullspace"), "not_avoiding": outcome(True, "sns"),
            "fixed_grasp": outcome(False, "fixed_grasp", min_m=-0.01)}
    comparison = Comparison(runs, _checks(runs))
    assert comparison.ok and comparison.status == "completed"
    lines = describe(comparison)
    fixed = next(x for x in lines if x.startswith("  fixed_grasp "))
    assert "41 samples, FAILED on range at t = 1.24 s; nearest -10.0 mm" in fixed
    assert "; penetration;" in fixed
    assert lines[lines.index(fixed) + 1] == f"      {failure['message']}"
    assert "NO" not in "\n".join(lines)


def test_each_runs_config_yaml_rebuilds_that_run(compared):
    _, out, _, _ = compared
    for folder, solver, enabled in zip(FOLDERS, ("nullspace", "nullspace", "fixed_grasp"),
                                       (True, False, False), strict=True):
        path = out / folder / "config.yaml"
        assert f"as '{folder}'" in path.read_text()
        exp = build_experiment(load_config(path), str(path))
        assert exp.solver_name == solver and exp.task.scene.settings.enabled is enabled


@pytest.mark.slow
def test_a_comparison_replaces_its_own_output_and_keeps_other_files(compared, tmp_path):
    config, _, _, _ = compared
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
