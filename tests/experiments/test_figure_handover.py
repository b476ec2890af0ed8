"""What the drawing process gets ahead of the run's trace: the trace itself, sent before
the run's files are written (and the same values as ``trajectory.csv`` gives back), and
the figures' axes, built while it waits (the same pictures)."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from test_figures import short_limits_experiment

from dualarm_qp.experiments import run as run_module
from dualarm_qp.experiments.figures import ready
from dualarm_qp.experiments.figures.canvas import png_bytes
from dualarm_qp.experiments.figures.run_figures import (
    closure_figure,
    grasp_figure,
    joints_figure,
    rates_figure,
    tracking_figure,
    write_run_figures,
)
from dualarm_qp.experiments.figures.rundata import PlotLimits, RunData, run_title
from dualarm_qp.experiments.outputs import csv_columns
from dualarm_qp.experiments.run import run_experiment


class Recorder:
    """A figure writer with ``submit``, as the drawing process: records what it is sent."""

    def __init__(self, out: Path) -> None:
        self.out = out
        self.events: list[str] = []
        self.data: RunData | None = None

    def submit(self, out: Path, exp, data: RunData) -> None:
        written = sorted(p.name for p in out.iterdir())
        self.events.append(f"submit, folder {written}")
        self.data = data

    def __call__(self, out: Path, exp) -> list[str]:
        self.events.append("wait")
        return write_run_figures(out, exp)

    def close(self) -> None:
        self.events.append(f"close, folder {sorted(p.name for p in self.out.iterdir())}")


def same_columns(a: RunData, b: RunData) -> bool:
    if list(a.columns) != list(b.columns):
        return False
    for name, values in a.columns.items():
        other = b.columns[name]
        if values.dtype != other.dtype:
            return False
        if values.dtype.kind == "f" and not np.array_equal(values, other, equal_nan=True):
            return False
        if values.dtype.kind != "f" and not np.array_equal(values, other):
            return False
    return True


def test_the_trace_is_sent_before_the_run_files_and_is_what_the_file_reads(tmp_path):
    exp = short_limits_experiment(tmp_path)
    figures = Recorder(tmp_path / "o")
    outcome = run_experiment(exp, tmp_path / "o", progress=False, figures=figures)
    assert figures.events == ["submit, folder []", "wait"]
    assert figures.data is not None
    assert same_columns(figures.data, RunData.read(tmp_path / "o" / "trajectory.csv"))
    assert outcome.summary["outputs"][:2] == ["trajectory.csv", "config.yaml"]


def test_a_failure_while_the_run_files_are_written_ends_the_drawing_first(tmp_path,
                                                                          monkeypatch):
    exp = short_limits_experiment(tmp_path)
    figures = Recorder(tmp_path / "o")

    def broken(path, source):
        raise OSError("disk full")

    monkeypatch.setattr(run_module, "write_resolved_config", broken)
    with pytest.raises(OSError, match="disk full"):
        run_experiment(exp, tmp_path / "o", progress=False, figures=figures)
    # ended while trajectory.csv was still there (before the set was removed), never awaited
    assert figures.events == ["submit, folder []", "close, folder ['trajectory.csv']"]
    assert not any((tmp_path / "o").iterdir())


def test_columns_with_nan_and_infinity_are_sent_as_the_file_reads_them(tmp_path):
    exp = short_limits_experiment(tmp_path)
    outcome = run_experiment(exp, tmp_path / "o", progress=False, plots=False)
    trace = outcome.result.trace
    extra = {"level": [np.nan, np.inf, *([-0.1 + 1e-17] * (len(trace) - 2))]}
    cols = csv_columns(trace, extra)
    run_module.write_trace_csv(tmp_path / "t.csv", trace, columns=cols)
    sent = RunData.from_columns(cols)
    assert same_columns(sent, RunData.read(tmp_path / "t.csv"))
    assert sent.columns["level"][1] == np.inf and np.isnan(sent.columns["level"][0])
    assert sent.columns["status"].dtype.kind == "U"  # text, as read


def pixels(png: bytes) -> np.ndarray:
    with Image.open(io.BytesIO(png)) as image:
        return np.asarray(image.convert("RGB"))


def test_the_axes_built_ahead_are_used_and_draw_the_same_figures(tmp_path):
    exp = short_limits_experiment(tmp_path)
    run_experiment(exp, tmp_path / "o", progress=False, plots=False)
    data = RunData.read(tmp_path / "o" / "trajectory.csv")
    limits = PlotLimits.from_experiment(exp)
    title = run_title(exp)
    draws = {"grasp": grasp_figure, "tracking": tracking_figure, "closure": closure_figure,
             "lanes:joints": joints_figure, "lanes:rates": rates_figure}
    fresh = {name: png_bytes(draw(data, limits, title)) for name, draw in draws.items()}
    try:
        ready.prepare()
        built = {name: ready._READY[name][0] for name in draws}
        for name, draw in draws.items():
            fig = draw(data, limits, title)
            assert fig is built[name], name  # the one built ahead, taken
            assert np.array_equal(pixels(png_bytes(fig)), pixels(fresh[name])), name
        assert set(ready._READY) == {"clearance"}  # each taken once; no clearance drawn
    finally:
        ready._READY.clear()
