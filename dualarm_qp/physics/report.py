"""The physics check's figure (``physics.png``) and its part of ``report.html``.

The figure shows, against time, for the rigid replay and the closed loop: the object's
deviation from ``D(t)``, the internal (squeeze) force, the follower's support force,
the largest share of a joint torque limit, and the grasp slip, each with its threshold.
"""

from __future__ import annotations

import html
from pathlib import Path
from typing import Any

import numpy as np

#: The figure's file name in a run folder.
PHYSICS_FIGURE = "physics.png"


def write_physics_figure(path: Path, runs: dict[str, dict[str, Any]],
                         physics: dict[str, Any]) -> None:
    """Draw the check's figure into ``path`` (atomically).

    Parameters
    ----------
    runs : dict
        ``"replay"`` and ``"closed_loop"``: their logs (:attr:`PhysicsRun.log
        <dualarm_qp.physics.check.PhysicsRun.log>`).
    physics : dict
        The ``physics`` section of ``summary.json`` (thresholds, verdict).
    """
    from ..experiments.figures.canvas import new_figure, save_png

    s = physics["settings"]
    fig = new_figure(figsize=(9.0, 10.0), layout="constrained")
    axes = fig.subplots(5, 1, sharex=True)
    panels = [
        ("deviation_pos", 1e3, "object off D(t) [mm]", s["deviation_max_m"] * 1e3),
        ("internal", 1.0, "internal force [N]", None),
        ("support", 1.0, "follower support [N]", 0.0),
        ("torque_ratio_peak", 1.0, "torque / limit", s["torque_ratio_max"]),
        ("slip", 1e3, "grasp slip [mm]", s["slip_max_m"] * 1e3),
    ]
    styles = {"replay": dict(color="C0", lw=1.0, label="rigid replay"),
              "closed_loop": dict(color="C1", lw=1.2, label="closed loop")}
    for ax, (key, scale, label, limit) in zip(axes, panels, strict=True):
        drawn = 0
        for name, log in runs.items():
            y = np.asarray(log[key], dtype=float) * scale
            if np.isnan(y).all():
                continue
            ax.plot(log["t"], y, gid=f"{name}:{key}", **styles[name])
            drawn += 1
        if not drawn:
            ax.text(0.5, 0.5, "no torque limits for these arms (physics.tau_max)",
                    transform=ax.transAxes, ha="center", va="center")
            limit = None
        if key == "internal":
            base = (physics["replay"] or {}).get("internal_force_max_N", 0.0)
            limit = base + s["squeeze_max_N"]
        if limit is not None:
            ax.axhline(limit, color="C3", ls="--", lw=0.8, gid=f"limit:{key}")
        ax.set_ylabel(label)
        ax.grid(True, alpha=0.3)
    axes[0].legend(loc="upper right", fontsize=8)
    axes[-1].set_xlabel("t [s]")
    cause = physics.get("cause")
    fig.suptitle(f"physics check: {physics['status']}" + (
        "" if cause is None else f" ({cause} from t = {physics['cause_t_s']:.3g} s)"))
    save_png(fig, path)


def physics_html(physics: dict[str, Any]) -> str:
    """Return the report's physics section: the verdict, its reasons, the peaks."""
    status = str(physics.get("status", ""))
    reasons = physics.get("reasons") or []
    good = status == "ok"
    parts = ['<h2 id="physics">Physics check (MuJoCo)</h2>',
             f'<p class="verdict {"completed" if good else "failed"}">physics.status: '
             f"<b>{html.escape(status)}</b>"
             + ("" if not reasons else ": " + html.escape("; ".join(map(str, reasons))))
             + "</p>"]
    if physics.get("cause") is not None:
        parts.append(f'<p class="note">Cause ({html.escape(str(physics["cause"]))}, from '
                     f't = {_num(physics.get("cause_t_s"))} s, sample '
                     f'{_num(physics.get("cause_sample"))}): '
                     f'{html.escape(str(physics.get("message", "")))}.</p>')
    elif physics.get("oscillation"):
        parts.append('<p class="note">Below every threshold: '
                     f'{html.escape(str(physics["oscillation"]["message"]))}.</p>')
    rows = []
    for key, label in (("deviation_pos_max_m", "object off D(t), max [m]"),
                       ("internal_force_max_N", "internal force, max [N]"),
                       ("follower_support_min_N", "follower support, min [N]"),
                       ("torque_ratio_max", "torque / limit, max"),
                       ("slip_max_m", "grasp slip, max [m]"),
                       ("wall_time_s", "wall time [s]")):
        cells = "".join(f'<td class="num">{_num((physics.get(run) or {}).get(key))}</td>'
                        for run in ("replay", "closed_loop"))
        rows.append(f"<tr><th>{html.escape(label)}</th>{cells}</tr>")
    parts.append("<table><tr><th></th><th>rigid replay</th><th>closed loop</th></tr>"
                 + "".join(rows) + "</table>")
    worst = (physics.get("closed_loop") or {}).get("torque_ratio_worst") or {}
    if worst.get("joint"):
        parts.append(f'<p class="note">Largest torque share in the closed loop: '
                     f'{html.escape(str(worst["joint"]))} at t = {_num(worst.get("t_s"))} '
                     "s.</p>")
    notes = physics.get("model_notes") or []
    if notes:
        parts.append('<p class="note">Model: ' + html.escape("; ".join(map(str, notes)))
                     + ".</p>")
    return "\n".join(parts)


def _num(value: Any) -> str:
    if value is None:
        return "n/a"
    if isinstance(value, float):
        return f"{value:.4g}" if np.isfinite(value) else "n/a"
    return html.escape(str(value))


__all__ = ["PHYSICS_FIGURE", "physics_html", "write_physics_figure"]
