"""Draw docs/figures/pillar_map.png: how the beam task ends for each place of the pillar.

Reads the ``results.csv`` of a ``configs/sweeps/pillar_map.yaml`` sweep and colours each
cell by its outcome: completed at full speed; completed, but the path was slowed near the
pillar (with the seconds lost: without the pillar no time is lost); stopped by a
collision pair (criterion ``collision``, with the share of the path done); refused before
the run because the path itself runs the beam into the pillar (``path_collision``); or
another failure. A star marks the
pillar's place in ``configs/puma_beam_pillar.yaml``. Run it with
``python docs/figures/pillar_map.py SWEEP_DIR [OUT.png]`` (default: next to this script),
after ``dualarm-qp sweep configs/sweeps/pillar_map.yaml --out SWEEP_DIR``.
"""

from __future__ import annotations

import csv
import sys
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.colors import ListedColormap
from matplotlib.patches import Patch

OUT = Path(__file__).with_suffix(".png")
X, Y = "scene.obstacles.0.pose.position.0", "scene.obstacles.0.pose.position.1"

#: Outcome -> (code, colour, legend).
OUTCOMES = {
    "completed": (0, "#1a9850", "completed"),
    "slowed": (1, "#a6d96a", "completed, the path slowed near the pillar (seconds lost)"),
    "collision": (2, "#fdae61", "stopped: a pair would come nearer than d_s (% of path done)"),
    "path_collision": (3, "#bababa", "refused: the path runs the beam into the pillar"),
    "other": (4, "#7b3294", "failed otherwise (% of path done)"),
}
FILE_PILLAR = (630.0, 1100.0)  # configs/puma_beam_pillar.yaml [mm]


def outcome(row: dict[str, str]) -> str:
    """Return the key of :data:`OUTCOMES` of one row of the table."""
    if row["status"] == "completed":
        return "slowed" if float(row["time_lost_to_scaling_s"]) > 0 else "completed"
    return row["criterion"] if row["criterion"] in ("collision", "path_collision") else "other"


def edges(levels: np.ndarray) -> np.ndarray:
    """Cell edges around sorted levels: the midpoints, and half a step beyond the ends."""
    mid = (levels[1:] + levels[:-1]) / 2
    return np.concatenate([[levels[0] - (mid[0] - levels[0])], mid,
                           [levels[-1] + (levels[-1] - mid[-1])]])


def main(folder: Path, out: Path) -> None:
    """Draw the map of the sweep in ``folder`` into ``out``."""
    with (folder / "results.csv").open(newline="") as fh:
        rows = list(csv.DictReader(fh))
    xs = np.array(sorted({float(r[X]) for r in rows}))
    ys = np.array(sorted({float(r[Y]) for r in rows}))
    grid = np.full((len(ys), len(xs)), np.nan)
    fig, ax = plt.subplots(figsize=(6.2, 7.0))
    for r in rows:
        i, j = int(np.searchsorted(ys, float(r[Y]))), int(np.searchsorted(xs, float(r[X])))
        kind = outcome(r)
        grid[i, j] = OUTCOMES[kind][0]
        if kind in ("collision", "other"):  # rounded down: 99.6 is not the whole path
            ax.text(xs[j], ys[i], f"{np.floor(float(r['path_completed_pct'])):.0f}",
                    ha="center", va="center", fontsize=7)
        elif kind == "slowed":
            ax.text(xs[j], ys[i], f"{float(r['time_lost_to_scaling_s']):.2g}", ha="center",
                    va="center", fontsize=7)
    cmap = ListedColormap([c for _, c, _ in OUTCOMES.values()])
    ax.pcolormesh(edges(xs), edges(ys), np.ma.masked_invalid(grid), cmap=cmap, vmin=-0.5,
                  vmax=len(OUTCOMES) - 0.5, edgecolors="white", linewidth=0.5)
    ax.plot(*FILE_PILLAR, marker="*", ms=11, mfc="white", mec="k", ls="none", zorder=5,
            label="the pillar in puma_beam_pillar.yaml")
    ax.set_xlabel("pillar x [mm]")
    ax.set_ylabel("pillar y [mm]")
    ax.set_aspect("equal")
    ax.set_title("The beam task with collision avoidance: where may the pillar stand?",
                 fontsize=10)
    handles = [Patch(color=c, label=text) for _, c, text in OUTCOMES.values()]
    handles.append(ax.get_legend_handles_labels()[0][0])
    fig.legend(handles=handles, loc="lower center", ncol=1, fontsize=8, frameon=False)
    fig.tight_layout(rect=(0, 0.15, 1, 1))
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    main(Path(sys.argv[1]), Path(sys.argv[2]) if len(sys.argv) > 2 else OUT)
