"""clearance.png and the report's clearance: a run with a collision scene, and without.

The test scene is the beam of configs/puma_beam_limits.yaml with a pillar beside the
follower: its link1 starts 42 mm from it, its link2 comes within the safety distance.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import yaml

from dualarm_qp.collision.settings import CLEARANCE_ALLOWANCE
from dualarm_qp.experiments import build_experiment, load_config
from dualarm_qp.experiments.figures import (
    CLEARANCE_FIGURE,
    RUN_FIGURES,
    PlotLimits,
    RunData,
    clearance_figure,
)
from dualarm_qp.experiments.html_report import render_run_report
from dualarm_qp.experiments.run import run_experiment

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
PILLAR = {"collision": {"enabled": True},
          "scene": {"obstacles": [{"name": "pillar", "capsule": {"radius": 50, "length": 1200},
                                   "pose": {"position": [450, 1230, 0]}}]}}


def pillar_experiment(folder: Path, duration: float = 0.62, enabled: bool = True):
    raw = yaml.safe_load((CONFIGS / "puma_beam_limits.yaml").read_text())
    raw.update(PILLAR, name="puma_beam_pillar")
    raw["collision"] = {"enabled": enabled}
    raw["controller"]["duration"] = duration  # 21 samples
    path = folder / "pillar.yaml"
    path.write_text(yaml.safe_dump(raw))
    return build_experiment(load_config(path), str(path))


@pytest.fixture(scope="module")
def pillar_run(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("pillar")
    exp = pillar_experiment(tmp)
    out = tmp / "out"
    run_experiment(exp, out, progress=False)
    return exp, out


def _levels(fig, gid: str) -> list[float]:
    return sorted(float(ln.get_ydata()[0]) for ax in fig.axes for ln in ax.get_lines()
                  if ln.get_gid() == gid)


def _lines(fig, prefix: str) -> dict:
    return {ln.get_gid(): ln for ax in fig.axes for ln in ax.get_lines()
            if (ln.get_gid() or "").startswith(prefix)}


def test_a_run_with_a_scene_writes_and_reports_its_clearance(pillar_run):
    _, out = pillar_run
    listed = json.loads((out / "summary.json").read_text())["outputs"]
    figures = [*RUN_FIGURES, CLEARANCE_FIGURE, "report.html"]
    assert [f for f in listed if f in figures] == figures  # clearance.png last of the PNGs
    assert (out / CLEARANCE_FIGURE).stat().st_size > 1000
    page = (out / "report.html").read_text()
    assert page.count('src="data:image/png;base64,') == len(RUN_FIGURES) + 1
    figure = page[page.index('<figure id="clearance.png">'):]
    assert "safety distance d_s" in figure[:figure.index("</figure>")]
    # the smallest clearance, in mm, with its pair, against d_s
    text = page[page.index('<p id="clearance">'):]
    text = text[:text.index("</p>")]
    assert "mm, follower.link1 - pillar" in text and "safety distance 20 mm" in text
    assert "allowance 1 mm: kept" in text
    assert "<th>clearance</th>" not in page  # not a row of the range and speed table


def test_a_task_without_a_scene_has_no_clearance(tmp_path):
    """Its run writes no clearance.png (tests/experiments/test_figures.py: its report)."""
    path = CONFIGS / "puma_beam_limits.yaml"
    exp = build_experiment(load_config(path), str(path))
    assert exp.task.scene is None and PlotLimits.from_experiment(exp).clearance is None
    page = render_run_report(tmp_path, {"experiment": "x", "status": "completed",
                                        "realised_limits": {}}, [])
    assert 'id="clearance"' not in page


def test_the_figure_draws_each_group_against_d_s_and_d_i(pillar_run):
    exp, out = pillar_run
    data = RunData.read(out / "trajectory.csv")
    limits = PlotLimits.from_experiment(exp)
    assert limits.clearance == pytest.approx((0.02, 0.1)) and limits.clearance_enforced
    fig = clearance_figure(data, limits)
    assert _levels(fig, "limit:safety_distance") == pytest.approx([20.0])  # mm
    assert _levels(fig, "limit:influence_distance") == pytest.approx([100.0])
    assert _levels(fig, "limit:clearance_allowance") == pytest.approx(
        [(0.02 - CLEARANCE_ALLOWANCE) * 1e3])
    groups = _lines(fig, "clearance:clearance_")
    # the beam's object has no shape: no arm-object pairs, an empty (inf) group not drawn
    assert set(groups) == {"clearance:clearance_arm_arm", "clearance:clearance_obstacles"}
    obstacles = data.col("clearance_obstacles")
    np.testing.assert_allclose(groups["clearance:clearance_obstacles"].get_ydata(),
                               np.minimum(obstacles, 0.3) * 1e3)
    lowest = _lines(fig, "clearance:min")["clearance:min"]
    assert float(lowest.get_ydata()[0]) == pytest.approx(obstacles.min() * 1e3)
    assert "follower.link1 - pillar" in lowest.get_label()


def test_a_breach_is_shaded_and_far_pairs_lie_on_the_top_edge(pillar_run):
    exp, out = pillar_run
    data = RunData.read(out / "trajectory.csv")
    cols = dict(data.columns)
    d = np.full(len(data), 0.5)  # far: above the axis' top (3 d_i)
    d[5:8] = 0.0185  # below d_s - allowance = 19 mm for three samples
    cols["clearance_obstacles"] = d
    fig = clearance_figure(RunData(cols), PlotLimits.from_experiment(exp))
    ax = fig.axes[0]
    shaded = [p for p in ax.patches if p.get_gid() == "outside:clearance"]
    assert len(shaded) == 1
    t = data.t
    x0, x1 = shaded[0].get_x(), shaded[0].get_x() + shaded[0].get_width()
    assert x0 < t[5] and t[7] < x1 < t[8]
    line = _lines(fig, "clearance:clearance_obstacles")["clearance:clearance_obstacles"]
    assert max(line.get_ydata()) == pytest.approx(300.0)
    assert any("on the top edge" in text.get_text() for text in ax.get_legend().get_texts())


def test_with_collision_avoidance_off_the_clearance_is_only_measured(pillar_run, tmp_path):
    _, out = pillar_run
    off = pillar_experiment(tmp_path, enabled=False)
    limits = PlotLimits.from_experiment(off)
    assert limits.clearance is not None and not limits.clearance_enforced
    fig = clearance_figure(RunData.read(out / "trajectory.csv"), limits)
    assert _levels(fig, "limit:clearance_allowance") == []
    assert "measured only" in fig.axes[0].get_title()
    summary = json.loads((out / "summary.json").read_text())
    clearance = dict(summary["realised_limits"]["clearance"], enforced=False, kept=False,
                     penetration=True, min_m=-0.004)
    page = render_run_report(tmp_path, {"experiment": "x", "status": "completed",
                                        "realised_limits": {"clearance": clearance}}, [])
    assert "-4 mm" in page and "NOT kept (collision avoidance off: measured only)" in page
    assert "the shapes overlap" in page


def test_clearance_png_is_a_run_output_that_a_rerun_replaces(pillar_run, tmp_path):
    from dualarm_qp.experiments.run import remove_run_outputs

    _, out = pillar_run
    for p in out.iterdir():
        (tmp_path / p.name).write_bytes(p.read_bytes())
    (tmp_path / "notes.txt").write_text("mine")
    assert CLEARANCE_FIGURE in remove_run_outputs(tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["notes.txt"]
