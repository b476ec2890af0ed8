"""Draw docs/figures/grasp_frames.png: the hands' tool frames, H1, the object and the grasp.

A side view of ``configs/panda_pair.yaml`` at t0: the bar lies level, both hands hold it
from above. Every frame is computed by the library (``dq.pose`` for the file's H1, the
plane bar's ``pose(sigma)`` for H2), so the picture shows what a run uses. Run it with
``python docs/figures/grasp_frames.py [OUT.png]`` (default: next to this script).
"""

from __future__ import annotations

import sys
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.patches import FancyArrowPatch, Rectangle

import dualarm_qp as dq

OUT = Path(__file__).with_suffix(".png")

#: The file's numbers (object section of configs/panda_pair.yaml).
H1 = dq.pose([600, 0, 0], rotation=[[0, 0, -1], [0, 1, 0], [1, 0, 0]],
             units={"length": "mm"})
BAR = dq.PlaneBar(r_min=[0, 0, 0.150], r_max=[0, 0, 0.550])
SIGMA = 0.300  # grasp_initial [m]

AXIS = {"x": "#d62728", "y": "#2ca02c", "z": "#1f77b4"}
LEADER, FOLLOWER = "#1f77b4", "#ff7f0e"
ARROW = 95.0  # drawn axis length [mm]


def page(v: np.ndarray) -> np.ndarray:
    """Object coordinates [m] to the page [mm]: right = -z, up = -x, out of the page = y."""
    return np.array([-v[2], -v[0]]) * 1e3


def draw_frame(ax: plt.Axes, T: np.ndarray, name: str, colour: str,
               label_side: float = 1.0) -> None:
    """Axes of the frame ``T`` (object <- frame): x and z as arrows, y as a dot or cross."""
    o = page(T[:3, 3])
    for i, axis in enumerate("xyz"):
        d = T[:3, i]
        if abs(d[1]) > 0.5:  # along the page normal
            offset = np.array([-30.0 * label_side, 20.0])
            sym = "$\\odot$" if d[1] > 0 else "$\\otimes$"
            ax.text(*(o + offset), sym, color=AXIS[axis], ha="center", va="center",
                    fontsize=15)
            ax.text(*(o + offset + np.array([-15.0, 0.0]) * label_side), axis,
                    color=AXIS[axis], ha="center", va="center", fontsize=10,
                    fontweight="bold")
            continue
        tip = o + page(d) * ARROW / 1e3
        ax.annotate("", xy=tip, xytext=o, zorder=6,
                    arrowprops={"arrowstyle": "-|>", "color": AXIS[axis], "lw": 2.2,
                                "mutation_scale": 14})
        ax.text(*(o + page(d) * (ARROW + 16.0) / 1e3), axis, color=AXIS[axis],
                ha="center", va="center", fontsize=10, fontweight="bold")
    ax.plot(*o, "o", color=colour, ms=6, zorder=7)
    ax.text(o[0], o[1] + 40.0, name, color=colour, ha="center", va="bottom", fontsize=9.5,
            fontweight="bold")


def draw_hand(ax: plt.Axes, T: np.ndarray, colour: str, arm_side: float) -> None:
    """Draw a hand from the side, holding the bar at ``T``, its arm leaving to ``arm_side``."""
    o = page(T[:3, 3])
    kw = {"color": colour, "lw": 0, "zorder": 3}
    ax.add_patch(Rectangle((o[0] - 17.0, -45.0), 34.0, 125.0, alpha=0.22, **kw))  # finger
    ax.add_patch(Rectangle((o[0] - 55.0, 80.0), 110.0, 35.0, alpha=0.35, **kw))   # palm
    ax.add_patch(Rectangle((o[0] - 30.0, 115.0), 60.0, 35.0, alpha=0.5, **kw))    # flange
    ax.plot([o[0], o[0] + 110.0 * arm_side], [150.0, 270.0], color=colour, lw=14,
            alpha=0.3, solid_capstyle="round", zorder=3)


def main(out: Path = OUT) -> None:
    """Draw the figure and write it to ``out``."""
    T_object_leader = np.linalg.inv(H1)
    H2 = BAR.pose(SIGMA)
    o_l, o_o, o_f = page(T_object_leader[:3, 3]), page(np.zeros(3)), page(H2[:3, 3])
    fig, ax = plt.subplots(figsize=(11.0, 5.6))
    # The bar (object x points down into it: its top face is x = 0).
    ax.add_patch(Rectangle((-760.0, -60.0), 800.0, 60.0, color="0.75", zorder=1))
    lo, hi = page(BAR.point(BAR.sigma_min))[0], page(BAR.point(BAR.sigma_max))[0]
    ax.add_patch(Rectangle((hi, -7.0), lo - hi, 7.0, color="#2ca02c", alpha=0.55, zorder=2))
    ax.text((o_l[0] + o_f[0]) / 2, -95.0, "grasp range (green)\n150..550 mm", ha="center",
            va="center", fontsize=9, color="#1b5e20")
    draw_hand(ax, T_object_leader, LEADER, arm_side=-1.0)
    draw_hand(ax, H2, FOLLOWER, arm_side=1.0)
    draw_frame(ax, np.eye(4), "object frame\nD(t) in the world", "0.2", label_side=-1.0)
    draw_frame(ax, T_object_leader, "leader's tool", LEADER)
    draw_frame(ax, H2, "follower's tool", FOLLOWER)
    # H1 and H2(sigma), from the frame they are expressed in to the frame they place.
    drop = np.array([0.0, -125.0])  # the arrows start below the frames' labels
    ax.add_patch(FancyArrowPatch(o_l + drop, o_o + drop, connectionstyle="arc3,rad=0.42",
                                 arrowstyle="-|>", mutation_scale=16, lw=1.6, ls="--",
                                 color=LEADER))
    ax.text((o_l[0] + o_o[0]) / 2, -290.0, "H1: the object frame in the leader's tool frame",
            color=LEADER, ha="center", va="center", fontsize=9.5)
    ax.add_patch(FancyArrowPatch(o_o + drop, o_f + drop, connectionstyle="arc3,rad=-0.45",
                                 arrowstyle="-|>", mutation_scale=16, lw=1.6, ls="--",
                                 color=FOLLOWER))
    ax.text(o_o[0] + 45.0, -185.0, "H2($\\sigma$) = surface.pose($\\sigma$):\nthe follower's "
            f"tool frame\nin the object frame\n($\\sigma$ = {SIGMA * 1e3:g} mm)",
            color=FOLLOWER, ha="left", va="center", fontsize=9.5)
    # The sliding direction s* and the grasp coordinate sigma.
    s_dir = page(BAR.tangent(SIGMA))
    tail = o_f + s_dir * 0.04 + [0.0, 175.0]
    ax.annotate("", xy=tail + s_dir * 0.17, xytext=tail,
                arrowprops={"arrowstyle": "-|>", "color": FOLLOWER, "lw": 2.5,
                            "mutation_scale": 16})
    ax.text(*(tail + s_dir * 0.085 + [0.0, 22.0]), "s*: the follower slides,\n$\\sigma$ grows",
            color=FOLLOWER, ha="center", va="bottom", fontsize=9.5)
    ax.text(0.01, 0.02,
            "Tool frames: x red, y green, z blue ($\\odot$ out of the page, $\\otimes$ into it)."
            "\nFollower (set by the surface): z = a* (approach, into the face), "
            "x = s* (sliding), y = a* $\\times$ s*.\n"
            "Leader (set by H1 = {position: [600, 0, 0], rotation: [[0, 0, -1], [0, 1, 0], "
            "[1, 0, 0]]}, mm): the columns of the rotation\nare the object's axes in the "
            "leader's tool frame (object x = tool z, object z = -tool x); the position is "
            "the object origin.",
            transform=ax.transAxes, fontsize=9, va="bottom", ha="left",
            bbox={"boxstyle": "round", "fc": "white", "ec": "0.8"})
    ax.set_title("Frames of a sliding grasp: configs/panda_pair.yaml at t0, side view",
                 fontsize=11)
    ax.set_xlim(-800.0, 330.0)
    ax.set_ylim(-450.0, 300.0)
    ax.set_aspect("equal")
    ax.axis("off")
    fig.tight_layout()
    fig.savefig(out, dpi=110, bbox_inches="tight", pad_inches=0.1)
    plt.close(fig)
    print(out)


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else OUT)
