"""A file with a collision scene, run with collision avoidance, without it, and fixed-grasp.

``dualarm-qp collisions CONFIG`` (:func:`compare_avoidance`) runs the file three ways, each
into a folder of its own:

- ``avoiding/``: as written, with ``collision.enabled: true`` (the file's solver, which
  must take rows: SNS, ``reference`` and ``fixed_grasp`` do not);
- ``not_avoiding/``: the same with ``collision.enabled: false``: the clearance is
  measured, not kept;
- ``fixed_grasp/``: Zheng and Luh's fixed grasp (solver ``fixed_grasp``), collision
  avoidance off (the method takes no rows);

then draws ``collisions.png``: each run's nearest clearance against time, with the
safety and influence distances, above its grasp coordinate against time. Each run
folder holds what ``dualarm-qp run`` writes; its ``config.yaml`` is the file as that run
ran it (``collision.enabled`` and ``solver`` set). ``collisions.json`` is written last: how
it ended, what was measured in each run (completed or not and why, the smallest
clearance and its pair, penetration, the grasp travel), the claims checked, and the list
of what was written. A new comparison into the same folder first removes those (and only
those).

The comparison claims one thing of any file (:data:`CLAIM`): the run with avoidance
completes and keeps the safety distance. Whether the other two runs complete or
penetrate is measured, not claimed: a file of your own need not be a story of a grasp
that runs into an obstacle. The shipped pillar demo is such a story; with
``expect_penetration`` (``--expect-penetration``) the comparison also claims that both
runs without avoidance penetrate (:data:`DEMO_CLAIMS`).
"""

from __future__ import annotations

import contextlib
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from .._io import write_text
from .._signals import SignalHold
from ..errors import ConfigError
from .config import ExperimentConfig, load_config
from .outputs import owned_entries, remove_owned, write_json
from .run import OUTPUT_FILES, RunOutcome, remove_run_outputs, run_and_write
from .setup import Experiment, build_experiment


@dataclass(frozen=True)
class Variant:
    """One way of running the file.

    Attributes
    ----------
    label : str
        Its folder and key in ``collisions.json``.
    title : str
        Legend text.
    avoid : bool
        ``collision.enabled``.
    solver : str or None
        Solver override (None: the file's).
    colour : str
        Matplotlib colour.
    """

    label: str
    title: str
    avoid: bool
    solver: str | None
    colour: str


#: The runs, in order.
VARIANTS = (
    Variant("avoiding", "sliding grasp, collision avoidance on", True, None, "C2"),
    Variant("not_avoiding", "sliding grasp, collision avoidance off", False, None, "C1"),
    Variant("fixed_grasp", "fixed grasp (Zheng-Luh), collision avoidance off", False,
            "fixed_grasp", "C0"),
)

#: Files a comparison writes into its output folder, besides a folder per run.
COMPARISON_FILES = ("collisions.json", "collisions.png")

#: The folders of the runs, in :data:`VARIANTS` order.
RUN_FOLDERS = tuple(v.label for v in VARIANTS)

#: The claim checked on every file: its key in ``collisions.json`` and its words.
CLAIM = ("avoiding_completes_and_keeps_clearance",
         "the run with avoidance completes and keeps the safety distance")

#: The pillar demo's story, claimed only on request (``expect_penetration``): run, key
#: and words.
DEMO_CLAIMS = (("not_avoiding", "not_avoiding_penetrates",
                "the run without avoidance penetrates"),
               ("fixed_grasp", "fixed_grasp_penetrates", "the fixed grasp penetrates"))

#: Each claim's words, by its key.
CLAIM_WORDS = {CLAIM[0]: CLAIM[1], **{key: text for _, key, text in DEMO_CLAIMS}}


@dataclass
class Comparison:
    """Outcome of :func:`compare_avoidance`.

    Attributes
    ----------
    runs : dict of str to RunOutcome
        The runs done, by label (fewer than :data:`VARIANTS` when interrupted).
    checks : dict
        What was measured in each run, and the claims (empty when interrupted).
    interrupted : str or None
        The label of the run an interrupt stopped.
    """

    runs: dict[str, RunOutcome]
    checks: dict[str, Any]
    interrupted: str | None = None

    @property
    def ok(self) -> bool:
        """Whether every run ran and every claim held (:data:`CLAIM`, :data:`DEMO_CLAIMS`).

        The runs without avoidance may fail or penetrate: that is measured, not claimed.
        """
        claims = self.checks.get("claims", {})
        return len(self.runs) == len(VARIANTS) and bool(claims) and all(claims.values())

    @property
    def status(self) -> str:
        """``"completed"``, ``"failed"`` or ``"interrupted"``."""
        if self.interrupted is not None:
            return "interrupted"
        return "completed" if self.ok else "failed"


def variant_experiments(config: str | Path) -> dict[str, Experiment]:
    """Build the file's experiment for every :data:`VARIANTS` entry.

    Raises
    ------
    ConfigError
        The file gives no collision scene (no obstacle, no object shape, avoidance off),
        or any error of :func:`~dualarm_qp.experiments.setup.build_experiment`.
    PairingError
        The file's solver takes no rows, so it cannot avoid collisions.
    """
    path = str(config)
    cfg = load_config(config)
    if not (cfg.collision.enabled or cfg.scene.obstacles or cfg.object.shape is not None):
        raise ConfigError("the file gives no collision scene: nothing to compare; give "
                          "scene.obstacles, object.shape or collision.enabled "
                          "(docs/collisions.md)", path=path, key="scene")
    return {v.label: build_experiment(_with_avoidance(cfg, v.avoid), path, solver=v.solver)
            for v in VARIANTS}


def _with_avoidance(cfg: ExperimentConfig, avoid: bool) -> ExperimentConfig:
    collision = cfg.collision.model_copy(update={"enabled": avoid})
    return cfg.model_copy(update={"collision": collision})


def is_comparison_folder(out: str | Path) -> bool:
    """Whether ``out`` is free for a comparison without ``--force``.

    It is when missing or empty, or when it holds an earlier comparison: its
    ``collisions.json``, or (one stopped before writing that) nothing but what a
    comparison writes.
    """
    out = Path(out)
    if not out.is_dir() or (out / "collisions.json").is_file():
        return True
    own = set(owned_entries(out, COMPARISON_FILES))
    for entry in out.iterdir():
        if entry.name in RUN_FOLDERS and entry.is_dir() and not entry.is_symlink():
            if set(entry.iterdir()) - set(owned_entries(entry, OUTPUT_FILES)):
                return False
        elif entry not in own:
            return False
    return True


def remove_comparison(out: Path) -> None:
    """Remove an earlier comparison's files from ``out``; other files stay.

    ``collisions.json`` goes first, then the figure, then each run's files (and its
    folder, when that leaves it empty). Signals are held meanwhile.
    """
    with SignalHold():
        (out / "collisions.json").unlink(missing_ok=True)
        remove_owned(out, COMPARISON_FILES)
        for name in RUN_FOLDERS:
            folder = out / name
            if folder.is_dir() and not folder.is_symlink():
                remove_run_outputs(folder)
                with contextlib.suppress(OSError):
                    folder.rmdir()  # only when empty


def _write_variant_config(folder: Path, variant: Variant, exp: Experiment) -> None:
    """Make the run's ``config.yaml`` say how this run ran: avoidance and solver as set."""
    path = folder / "config.yaml"
    if not path.is_file():
        return
    data = yaml.safe_load(path.read_text())
    data.setdefault("collision", {})["enabled"] = variant.avoid
    if variant.solver is not None:
        data["solver"] = {"name": exp.solver_name}  # the file's options are its solver's
    header = "".join(line + "\n" for line in path.read_text().splitlines()
                     if line.startswith("#"))
    write_text(path, header + f"# Run by 'dualarm-qp collisions' as '{variant.label}': "
               f"collision.enabled {str(variant.avoid).lower()}, solver "
               f"{exp.solver_name}.\n" + yaml.safe_dump(data, sort_keys=False))


def nearest_clearance(outcome: RunOutcome) -> np.ndarray:
    """Return the nearest pair's distance at each sample of a run [m] (``inf``: no pair)."""
    tr = outcome.result.trace
    groups = np.vstack([tr.clearance_arm_arm, tr.clearance_arm_object,
                        tr.clearance_obstacles, tr.clearance_self])
    return np.asarray(np.fmin.reduce(groups, axis=0), dtype=float)


def _run_checks(label: str, outcome: RunOutcome) -> dict[str, Any]:
    s = outcome.summary
    clearance = s["realised_limits"].get("clearance") or {}
    minimum = clearance.get("min_m")
    failure = s.get("failure") or {}
    return {"folder": f"{label}/", "solver": s["solver"],
            "collision_avoidance": bool(clearance.get("enforced", False)),
            "status": s["status"], "samples": s["samples"],
            "failure": ({k: failure.get(k) for k in ("criterion", "sample", "t_s", "message")}
                        if failure else None),
            "clearance_min_m": minimum, "clearance_pair": clearance.get("pair"),
            "clearance_sample": clearance.get("sample"),
            "clearance_kept": clearance.get("kept"),
            "penetration": bool(minimum is not None and minimum < 0.0),
            "grasp_start_m": s.get("grasp_start_m"), "grasp_end_m": s.get("grasp_end_m"),
            "time_lost_to_scaling_s": s.get("time_lost_to_scaling_s")}


def _checks(runs: dict[str, RunOutcome], *, expect_penetration: bool = False
            ) -> dict[str, Any]:
    """Return what each run measured, and the claims.

    :data:`CLAIM`, and with ``expect_penetration`` :data:`DEMO_CLAIMS`.
    """
    checks: dict[str, Any] = {k: _run_checks(k, r) for k, r in runs.items()}
    checks["claims"] = {CLAIM[0]: bool(runs["avoiding"].ok
                                       and checks["avoiding"]["clearance_kept"])}
    if expect_penetration:
        for label, key, _ in DEMO_CLAIMS:
            checks["claims"][key] = checks[label]["penetration"]
    return checks


def _draw(out: Path, runs: dict[str, RunOutcome], exps: dict[str, Experiment]) -> None:
    """Draw ``collisions.png`` from the runs."""
    from .figures import Curve, DisplayUnits
    from .figures.avoidance import avoidance_figure
    from .figures.canvas import save_png

    exp = exps["avoiding"]
    scene = exp.task.scene
    assert scene is not None  # variant_experiments refuses a file without one
    units = DisplayUnits.of_file(exp.path)
    clearances, grasps = [], []
    for v in VARIANTS:
        run = runs[v.label]
        tr = run.result.trace
        d = nearest_clearance(run)
        c = run.summary["realised_limits"].get("clearance") or {}
        nearest = ("" if c.get("min_m") is None else
                   f": nearest {c['min_m'] * units.per_m:.1f} {units.length} ({c['pair']})")
        failed = "" if run.ok else f", {run.summary['status'].upper()}"
        label = f"{v.title} [{run.summary['solver']}]{failed}{nearest}"
        clearances.append(Curve(label, tr.t, d, v.colour))
        grasps.append(Curve(label, tr.t, tr.grasp, v.colour))
    surface = exp.task.surface
    note = ("The nearest clearance is the smallest distance of any checked pair at each "
            "sample, measured from the recorded joints.\nWith avoidance on, no pair "
            "approaches faster than allowed inside d_i, and none comes nearer than d_s.")
    fig = avoidance_figure(
        clearances, grasps, safety_distance=scene.settings.safety_distance,
        influence_distance=scene.settings.influence_distance,
        grasp_range=(surface.sigma_min, surface.sigma_max), scale=units.per_m,
        unit=units.length, title=f"{exp.name}: clearance with and without collision "
        "avoidance, and where the follower holds the object", note=note)
    save_png(fig, out / "collisions.png")


def _write_record(out: Path, config: str, runs: dict[str, RunOutcome],
                  checks: dict[str, Any], figures: list[str], interrupted: str | None,
                  settings: dict[str, Any]) -> None:
    """Write ``collisions.json``: what this comparison wrote, and how it ended."""
    rep = Comparison(runs, checks, interrupted)
    write_json(out / "collisions.json", {
        "status": rep.status,
        "config": config,
        "interrupted_run": interrupted,
        "collision": settings,
        "runs": {k: checks.get(k) or {"folder": f"{k}/", "status": r.summary["status"]}
                 for k, r in runs.items()},
        "claims": checks.get("claims", {}),
        "figures": figures,
        "outputs": [f"{k}/" for k in runs] + figures,
    })


def compare_avoidance(config: str | Path, out_dir: str | Path, *,
                      progress: bool | None = None, plots: bool = True,
                      animate: bool = False, expect_penetration: bool = False) -> Comparison:
    """Run an experiment file with and without collision avoidance, and with a fixed grasp.

    An earlier comparison in ``out_dir`` is replaced (:func:`remove_comparison`); other
    files there stay.

    Parameters
    ----------
    config : path
        An experiment file with a collision scene.
    out_dir : path
        Each run goes to ``out_dir/<label>/`` (:data:`VARIANTS`); ``collisions.png`` and
        ``collisions.json`` to ``out_dir``.
    progress : bool, optional
        Progress bars (default: when attached to a terminal).
    plots : bool
        Each run's own figures and ``report.html`` (the comparison's figure is always
        drawn).
    animate : bool
        Each run's ``animation.html``.
    expect_penetration : bool
        Also claim that both runs without avoidance penetrate (:data:`DEMO_CLAIMS`, the
        pillar demo's story); otherwise that is only measured.

    Returns
    -------
    Comparison
        When an interrupt (Ctrl-C, SIGTERM) stopped a run, that run is written as
        interrupted, the later ones are not run, no figure is drawn, and
        ``collisions.json`` says so. An interrupt that comes elsewhere is raised as
        KeyboardInterrupt once ``collisions.json`` records the same.

    Raises
    ------
    ConfigError, PairingError
        As :func:`variant_experiments`, before anything is written.
    """
    exps = variant_experiments(config)  # bad input: refused before anything is written
    scene = exps["avoiding"].task.scene
    assert scene is not None
    settings = {k: v for k, v in scene.settings.summary().items() if k != "enabled"}
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    remove_comparison(out)
    runs: dict[str, RunOutcome] = {}
    held: SignalHold | None = None
    label = VARIANTS[0].label
    try:
        for v in VARIANTS:
            label = v.label
            exp = exps[v.label]
            runs[v.label], hold = run_and_write(exp, out / v.label, progress=progress,
                                                plots=plots, animate=animate)
            with SignalHold():
                _write_variant_config(out / v.label, v, exp)
            if runs[v.label].interrupted or hold.signum is not None:
                held = hold
                break
    except KeyboardInterrupt:
        with SignalHold():
            _write_record(out, str(config), runs, {}, [], label, settings)
        raise
    if held is not None:  # stopped: no figure, no checks
        with SignalHold():
            _write_record(out, str(config), runs, {}, [], label, settings)
        held.deliver()
        return Comparison(runs, {}, label)
    with SignalHold():
        _draw(out, runs, exps)
        checks = _checks(runs, expect_penetration=expect_penetration)
        _write_record(out, str(config), runs, checks, ["collisions.png"], None, settings)
    return Comparison(runs, checks)


def describe(comparison: Comparison) -> list[str]:
    """Return the console lines summing a comparison up.

    What each run measured (completed or not and why, the smallest clearance and its
    pair, penetration or not, the grasp travel), then each claim (``yes`` or ``NO``).
    """
    lines = []
    for v in VARIANTS:
        run = comparison.runs.get(v.label)
        if run is None:
            continue
        s = run.summary
        c = comparison.checks.get(v.label, {})
        failure = c.get("failure")
        status = (s["status"] if run.ok or failure is None else
                  f"{s['status'].upper()} on {failure['criterion']} at t = "
                  f"{failure['t_s']:.3g} s")
        line = f"  {v.label:<13} {s['solver']:<12} {s['samples']:4d} samples, {status}"
        if c:
            line += f"; {_clearance_text(c)}"
            if s["samples"]:
                line += (f"; grasp {s['grasp_start_m'] * 1e3:.1f} -> "
                         f"{s['grasp_end_m'] * 1e3:.1f} mm")
        lines.append(line)
        if failure is not None and not run.ok:
            lines.append(f"      {failure['message']}")
    for claim, held in comparison.checks.get("claims", {}).items():
        lines.append(f"  {'yes' if held else 'NO '}  {CLAIM_WORDS[claim]}")
    return lines


def _clearance_text(c: dict[str, Any]) -> str:
    """Return what a run measured of its clearance: the smallest, its pair, penetration."""
    minimum = c.get("clearance_min_m")
    if minimum is None or not math.isfinite(minimum):
        return "no clearance measured"
    kept = ("" if not c["collision_avoidance"] else
            ", safety distance kept" if c["clearance_kept"] else
            ", safety distance NOT KEPT")
    return (f"nearest {minimum * 1e3:.1f} mm ({c['clearance_pair']}){kept}; "
            + ("penetration" if c["penetration"] else "no penetration"))


__all__ = ["CLAIM", "CLAIM_WORDS", "COMPARISON_FILES", "DEMO_CLAIMS", "RUN_FOLDERS",
           "VARIANTS", "Comparison", "Variant", "compare_avoidance", "describe",
           "is_comparison_folder", "nearest_clearance", "remove_comparison",
           "variant_experiments"]
