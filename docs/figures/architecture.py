"""Draw docs/figures/architecture.png: the parts of a step and the way one step takes.

Run ``python docs/figures/architecture.py`` from the repository root.
"""

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
from matplotlib.patches import FancyArrowPatch, FancyBboxPatch

OUT = Path(__file__).with_name("architecture.png")

BOXES = {
    # name: (x, y, w, h, colour, text)
    "state": (0.2, 6.2, 2.4, 0.9, "#dbe9f6", "measured state\njoints, grasps, path time"),
    "context": (3.3, 6.2, 3.6, 0.9, "#dbe9f6",
                "1. context (kernel.Context)\nkinematics once: poses, Jacobians,\n"
                "rate ranges, last command"),
    "tasks": (0.2, 4.3, 2.6, 1.3, "#e6f4e6",
              "2. tasks: equality(ctx)\nobject follows D(t)\ngrasp closure\nyours (rows or weighted)"),
    "cost": (3.0, 4.3, 2.0, 1.3, "#e6f4e6", "3. cost terms:\nquadratic(ctx)\ncentring\nyours"),
    "limits": (5.2, 4.3, 4.3, 1.3, "#e6f4e6",
               "4. limits: constraint(ctx)\nrange, speed, acceleration, collision\n"
               "(compiled), torque, yours (Python,\nasked by the same loop)"),
    "builder": (1.2, 2.9, 6.6, 0.8, "#fff2cc",
                "5. stack: rows under rows, costs summed, boxes intersected (named)"),
    "problem": (2.0, 1.8, 4.6, 0.8, "#fff2cc",
                "StepProblem: A x = s b, lower <= x <= upper, G x <= h, cost"),
    "pairing": (7.0, 1.8, 2.5, 0.8, "#f8d7da",
                "pairing check\n(rows, a full cost:\na solver that takes them)"),
    "policy": (0.2, 0.6, 3.0, 0.9, "#fde2cf", "6. solve_step: policy\nscale / relax / stop, fallback"),
    "solver": (3.5, 0.6, 2.6, 0.9, "#fde2cf", "solver (registry)\nnullspace, qp:*, SNS, ..."),
    "certify": (6.4, 0.6, 3.1, 0.9, "#f8d7da",
                "7. certify once: feasibility +\nexact optimum (KKT) -> status"),
    "controller": (0.2, -0.8, 4.6, 0.9, "#dbe9f6",
                   "8. guards: look-ahead (error budget),\nescape at a singularity; 9. apply"),
    "rollout": (5.1, -0.8, 4.4, 0.9, "#dbe9f6",
                "rollout: record trajectory.csv,\nrealised check (ranges, speeds, accelerations)"),
}
#: (from box, its side, to box, its side): sides are "top", "bottom", "left", "right".
ARROWS = [("state", "right", "context", "left"), ("context", "bottom", "tasks", "top"),
          ("context", "bottom", "cost", "top"), ("context", "bottom", "limits", "top"),
          ("tasks", "bottom", "builder", "top"), ("cost", "bottom", "builder", "top"),
          ("limits", "bottom", "builder", "top"), ("builder", "bottom", "problem", "top"),
          ("builder", "bottom", "pairing", "top"), ("problem", "bottom", "policy", "top"),
          ("policy", "right", "solver", "left"), ("solver", "right", "certify", "left"),
          ("policy", "bottom", "controller", "top"),
          ("controller", "right", "rollout", "left")]


def anchor(name: str, side: str) -> tuple[float, float]:
    """Return the middle of one side of a box (a little outside it)."""
    x, y, w, h, _, _ = BOXES[name]
    return {"top": (x + w / 2, y + h + 0.05), "bottom": (x + w / 2, y - 0.05),
            "left": (x - 0.05, y + h / 2), "right": (x + w + 0.05, y + h / 2)}[side]


def main() -> None:
    """Draw and save the picture."""
    fig, ax = plt.subplots(figsize=(11, 8.2))
    for x, y, w, h, colour, text in BOXES.values():
        ax.add_patch(FancyBboxPatch((x, y), w, h, boxstyle="round,pad=0.05",
                                    facecolor=colour, edgecolor="#444444"))
        ax.text(x + w / 2, y + h / 2, text, ha="center", va="center", fontsize=9)
    for a, side_a, b, side_b in ARROWS:
        ax.add_patch(FancyArrowPatch(anchor(a, side_a), anchor(b, side_b), arrowstyle="-|>",
                                     mutation_scale=12, color="#555555"))
    # The certificate answers the policy; the next sample starts from the recorded state.
    ax.add_patch(FancyArrowPatch(anchor("certify", "bottom"), anchor("policy", "bottom"),
                                 arrowstyle="-|>", mutation_scale=12, color="#b03a2e",
                                 linestyle="--", connectionstyle="arc3,rad=-0.06"))
    ax.text(4.8, 0.28, "the certified status", ha="center", fontsize=8, color="#b03a2e")
    ax.add_patch(FancyArrowPatch((9.85, -0.35), (9.85, 6.65), arrowstyle="-|>",
                                 mutation_scale=12, color="#1f4e79",
                                 connectionstyle="arc3,rad=-0.0"))
    ax.add_patch(FancyArrowPatch((9.85, 6.65), anchor("context", "right"),
                                 arrowstyle="-|>", mutation_scale=12, color="#1f4e79"))
    ax.text(9.95, 3.0, "next sample", rotation=90, va="center", fontsize=8,
            color="#1f4e79")
    # Steps 1-5 are one kernel call: kernel.Step.build, the one loop.
    ax.add_patch(FancyBboxPatch((0.05, 2.75), 9.6, 4.5, boxstyle="round,pad=0.05",
                                facecolor="none", edgecolor="#1f4e79", linestyle=":"))
    ax.text(9.6, 2.82, "one kernel call: kernel.Step.build", ha="right", fontsize=8,
            color="#1f4e79")
    ax.text(5.0, 7.45, "One control step: one loop asks every part in turn, stacks them, "
            "one certified solve", ha="center", fontsize=11, weight="bold")
    ax.set_xlim(-0.1, 10.1)
    ax.set_ylim(-1.1, 7.7)
    ax.axis("off")
    fig.tight_layout()
    fig.savefig(OUT, dpi=110)


if __name__ == "__main__":
    main()
