"""Reproduce the paper's Sec. 4 example: the three PUMA beam cases and Figs. 5 and 6.

Beside the paper's cases (a), (b), (c), a case (d) runs case (b) with joint and
sliding speed limits and a hard-limit solver; the figures draw it with the others.


A reproduction owns, in its output folder, ``reproduce.json`` (written last: it lists
what was written), ``report.html`` (the page that leads to each case,
:mod:`.reproduce_page`), the two figures and a folder per case with that case's run
outputs. A new reproduction into the same folder first removes those (and only those).
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from .._signals import SignalHold
from .config import load_config
from .outputs import owned_entries, remove_owned, write_json
from .reproduce_page import write_reproduction_report
from .run import OUTPUT_FILES, RunOutcome, remove_run_outputs, run_and_write
from .setup import Experiment, build_experiment

#: The cases run: (label, config file name). (a), (b), (c) are the paper's; (d) is
#: case (b) with speed limits and the ``nullspace`` solver (not in the paper).
CASES = (
    ("a", "puma_beam_fixed.yaml"),
    ("b", "puma_beam_sliding_s7_100.yaml"),
    ("c", "puma_beam_sliding_s7_1000.yaml"),
    ("d", "puma_beam_limits.yaml"),
)

#: The case with hard limits, whose speed limits the figures draw.
LIMITS_CASE = "d"


#: Files a reproduction writes into its output folder, besides a folder per case.
REPRODUCE_FILES = ("reproduce.json", "report.html", "fig5_joint3.png", "fig6_grasp.png")

#: The folders of the cases, in :data:`CASES` order.
CASE_FOLDERS = tuple(f"case_{label}" for label, _ in CASES)

#: What ``dualarm-qp bench`` compares when given no config: the beam task with speed
#: limits and the curved bar (the paper's own configs have no speed limits, where a
#: hard-limit solver's first, unlimited step tears the grasp closure open).
BENCH_CONFIGS = ("puma_beam_limits.yaml", "curved_bar_waypoints.yaml")


def bundled_config(name: str) -> Path:
    """Path of a configuration file shipped with the package."""
    return Path(str(resources.files("dualarm_qp") / "data" / name))


_JUMP_NOTE = ("(a)-(c): the paper's step, no speed limit; Table 2 starts outside the ranges, "
              "so (b), (c) jump in the first sample.\n(d): case (b) with the speed limits "
              "(dashed). Shaded: outside the range / over the limit, in the case's colour.")


@dataclass
class Reproduction:
    """Outcome of :func:`reproduce`: one run per case plus the paper's checks.

    Attributes
    ----------
    runs : dict of str to RunOutcome
        The cases run, by label (fewer than :data:`CASES` when interrupted).
    checks : dict
        The paper's checks (empty when interrupted).
    interrupted : str or None
        The label of the case an interrupt stopped.
    """

    runs: dict[str, RunOutcome]
    checks: dict[str, Any]
    interrupted: str | None = None

    @property
    def ok(self) -> bool:
        """Whether every case ran and completed."""
        return len(self.runs) == len(CASES) and all(r.ok for r in self.runs.values())

    @property
    def status(self) -> str:
        """``"completed"``, ``"failed"`` or ``"interrupted"``."""
        if self.interrupted is not None:
            return "interrupted"
        return "completed" if self.ok else "failed"


def is_reproduction_folder(out: str | Path) -> bool:
    """Whether ``out`` is free for a reproduction without ``--force``.

    It is when missing or empty, or when it holds an earlier reproduction: its
    ``reproduce.json``, or (a reproduction stopped before writing that) nothing but
    what a reproduction writes.
    """
    out = Path(out)
    if not out.is_dir() or (out / "reproduce.json").is_file():
        return True
    own = set(owned_entries(out, REPRODUCE_FILES))
    for entry in out.iterdir():
        if entry.name in CASE_FOLDERS and entry.is_dir() and not entry.is_symlink():
            if set(entry.iterdir()) - set(owned_entries(entry, OUTPUT_FILES)):
                return False
        elif entry not in own:
            return False
    return True


def remove_reproduction(out: Path) -> None:
    """Remove an earlier reproduction's files from ``out``; other files stay.

    ``reproduce.json`` goes first, then the figures, then each case's run files
    (and the case folder, when that leaves it empty). Signals are held meanwhile.
    """
    with SignalHold():
        (out / "reproduce.json").unlink(missing_ok=True)
        remove_owned(out, REPRODUCE_FILES)
        for name in CASE_FOLDERS:
            folder = out / name
            if folder.is_dir() and not folder.is_symlink():
                remove_run_outputs(folder)
                with contextlib.suppress(OSError):
                    folder.rmdir()  # only when empty


def _joint3_excursion(outcome: RunOutcome) -> dict[str, float]:
    tr = outcome.result.trace
    margin = tr.margin_qf[:, 2]
    outside = margin < -1e-9
    return {
        "q3_min_deg": float(np.rad2deg(np.min(tr.q_f[:, 2]))),
        "q3_max_deg": float(np.rad2deg(np.max(tr.q_f[:, 2]))),
        "q3_margin_min_deg": float(np.rad2deg(np.min(margin))),
        "q3_samples_outside": int(np.count_nonzero(outside)),
        "q3_time_outside_s": float(np.count_nonzero(outside) * outcome.result.dt),
    }


def _case_config(config_dir: str | Path | None, fname: str) -> Path:
    return Path(config_dir) / fname if config_dir is not None else bundled_config(fname)


def _write_record(out: Path, runs: dict[str, RunOutcome], checks: dict[str, Any],
                  figures: list[str], interrupted: str | None) -> None:
    """Write ``report.html`` and then ``reproduce.json``: what was written, how it ended."""
    rep = Reproduction(runs, checks, interrupted)
    record = {
        "status": rep.status,
        "interrupted_case": interrupted,
        "cases": {k: r.summary for k, r in runs.items()},
        "checks": checks,
        "figures": figures,
    }
    page = write_reproduction_report(out, record)
    write_json(out / "reproduce.json", {
        **record, "outputs": [f"case_{k}/" for k in runs] + figures + [page]})


def reproduce(out_dir: str | Path, *, config_dir: str | Path | None = None,
              progress: bool | None = None) -> Reproduction:
    """Run cases (a) to (d), draw Fig. 5 (follower q3) and Fig. 6 (grasp), write the page.

    An earlier reproduction in ``out_dir`` is replaced (:func:`remove_reproduction`);
    other files there stay. ``out_dir/report.html`` leads to each case (what it is,
    how it ended, its key numbers, links to its report and animation), lists the
    paper's claims and shows the figures; ``reproduce.json`` comes last.

    Parameters
    ----------
    out_dir : path
        Each case goes to ``out_dir/case_<x>/``; the figures, ``report.html`` and
        ``reproduce.json`` to ``out_dir``.
    config_dir : path, optional
        Where the YAML files of :data:`CASES` are; default: the copies shipped with the
        package (identical to the repository's ``configs/``).
    progress : bool, optional
        Progress bars (default: when attached to a terminal).

    Returns
    -------
    Reproduction
        When an interrupt (Ctrl-C, SIGTERM) stopped a case's rollout, that case is
        written as interrupted, the later ones are not run, no figure is drawn, and
        ``report.html`` and ``reproduce.json`` say so (``status: interrupted``). An
        interrupt that comes elsewhere (while files are written, between cases) is
        raised as KeyboardInterrupt once they record the same.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    remove_reproduction(out)
    runs: dict[str, RunOutcome] = {}
    exps: dict[str, Experiment] = {}
    held: SignalHold | None = None
    label = CASES[0][0]
    try:
        for label, fname in CASES:
            path = _case_config(config_dir, fname)
            exp = exps[label] = build_experiment(load_config(path), str(path))
            runs[label], hold = run_and_write(exp, out / f"case_{label}", progress=progress,
                                              animate=True)  # case_x/animation.html
            if runs[label].interrupted or hold.signum is not None:
                held = hold
                break
    except KeyboardInterrupt:
        with SignalHold():
            _write_record(out, runs, {}, [], label)
        raise
    if held is not None:  # stopped: no figures, no checks
        with SignalHold():
            _write_record(out, runs, {}, [], label)
        held.deliver()
        return Reproduction(runs, {}, label)
    with SignalHold():
        checks = _figures_and_checks(out, runs, exps)
        _write_record(out, runs, checks, ["fig5_joint3.png", "fig6_grasp.png"], None)
    return Reproduction(runs, checks)


def _draw_figures(out: Path, runs: dict[str, RunOutcome],
                  exps: dict[str, Experiment]) -> None:
    """Draw Fig. 5 (follower q3) and Fig. 6 (grasp) of the cases, with case (d)'s limits."""
    from .figures import Curve, DisplayUnits, comparison_figure
    from .figures.canvas import save_png

    colours = {"a": "C0", "b": "C1", "c": "C2", "d": "C4"}
    limited = exps[LIMITS_CASE]
    follower, surface = limited.task.follower, limited.task.surface
    units = DisplayUnits.of_file(limited.path)  # the paper's files: deg and mm

    def label(k: str) -> str:
        return f"({k}) {runs[k].summary['experiment']} [{runs[k].summary['solver']}]"

    q3 = [Curve(label(k), r.result.trace.t, r.result.trace.q_f[:, 2], colours.get(k, "C5"))
          for k, r in runs.items()]
    fig = comparison_figure(q3, value_range=(follower.q_min[2], follower.q_max[2]),
                            speed_limit=float(follower.qd_max[2]), scale=units.per_rad,
                            unit=units.angle, value_label=f"follower q3 [{units.angle}]",
                            speed_label=f"follower q3 rate, realised [{units.angle}/s]",
                            title="Fig. 5: follower joint 3 (dashed: its range and the "
                            "speed limit of case (d))", note=_JUMP_NOTE)
    save_png(fig, out / "fig5_joint3.png")
    sliding = [k for k in runs if k != "a"]  # (a) holds the grasp
    grasp = [Curve(label(k), runs[k].result.trace.t, runs[k].result.trace.grasp,
                   colours.get(k, "C5")) for k in sliding]
    speed = limited.options.grasp_speed_max if limited.options.velocity_limits else None
    fig = comparison_figure(grasp, value_range=(surface.sigma_min, surface.sigma_max),
                            speed_limit=speed, scale=units.per_m, unit=units.length,
                            value_label=f"grasp r2_z [{units.length}]",
                            speed_label=f"sliding speed, realised [{units.length}/s]",
                            title="Fig. 6: follower grasp position (dashed: the grasp range "
                            "of Eq. 3 and the sliding speed limit of case (d); case (a) "
                            "holds 450 mm)", note=_JUMP_NOTE)
    save_png(fig, out / "fig6_grasp.png")


def _first_step(outcome: RunOutcome) -> dict[str, float]:
    """How far the first sample moved the follower's q3 [deg] and the grasp [mm]."""
    tr = outcome.result.trace
    if len(tr) < 2:
        return {}
    return {"q3_first_step_deg": float(np.rad2deg(abs(tr.q_f[1, 2] - tr.q_f[0, 2]))),
            "grasp_first_step_mm": float(abs(tr.grasp[1] - tr.grasp[0]) * 1e3)}


def _figures_and_checks(out: Path, runs: dict[str, RunOutcome],
                        exps: dict[str, Experiment]) -> dict[str, Any]:
    """Draw Figs. 5 and 6 from the cases and return the paper's checks."""
    _draw_figures(out, runs, exps)
    checks: dict[str, Any] = {k: {**_joint3_excursion(r), **_first_step(r)}
                              for k, r in runs.items()}
    for k in ("b", "c", "d"):
        g = runs[k].result.trace.grasp
        checks[k]["grasp_start_mm"] = float(g[0] * 1e3)
        checks[k]["grasp_end_mm"] = float(g[-1] * 1e3)
        checks[k]["grasp_travel_first_10_steps_mm"] = float(abs(g[min(10, len(g) - 1)] - g[0])
                                                            * 1e3)
    checks["claims"] = {
        "case_a_leaves_joint3_range": checks["a"]["q3_samples_outside"] > 0,
        "case_b_joint3_inside": checks["b"]["q3_samples_outside"] == 0,
        "case_c_joint3_inside": checks["c"]["q3_samples_outside"] == 0,
        "case_c_moves_less_at_start": checks["c"]["grasp_travel_first_10_steps_mm"]
        < checks["b"]["grasp_travel_first_10_steps_mm"],
    }
    return checks
