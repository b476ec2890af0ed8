"""Add a limit of your own: a wall the follower's tool may not cross.

A limit is a small object with a ``name``, a ``gives_rows`` flag and one method,
``constraint(ctx)``, that returns boxes on variables and/or rows ``G x <= h``
(``dualarm_qp.step.parts``). The step's context ``ctx`` holds the state and its
kinematics, computed once per step: here the follower's tool position ``T_f`` [m] and
its Jacobian ``J_f``; ``ctx.layout`` says which entries of the decision vector ``x`` are
the follower's joint rates.

The wall is the plane ``normal . p = offset``; the tool must stay on the side where
``normal . p <= offset - margin``. Over one sample the tool moves by ``dt J_f qf_dot``,
so the row is ``normal^T J_f qf_dot <= (offset - margin - normal . p) / dt``.

The paper's beam task slides the follower's grasp 300 mm towards the leader; a wall
150 mm from the tool's start stops that, and the follower carries the beam with its
joints instead. Every solver that takes rows keeps the wall in the recorded motion;
SNS takes boxes only and is refused before anything runs.

Run it with ``python examples/custom_limit.py``.
"""

from pathlib import Path

import numpy as np

import dualarm_qp as dq


class Wall:
    """The follower's tool stays on the near side of a plane (a limit that gives one row)."""

    name = "wall"
    gives_rows = True

    def __init__(self, normal, offset, margin=1e-3):
        self.normal = np.asarray(normal, dtype=float)  # unit normal, pointing to the wall
        self.offset, self.margin = float(offset), float(margin)  # [m]

    def constraint(self, ctx):
        """One row: the tool's motion towards the wall over one sample fits the gap."""
        G = np.zeros((1, ctx.layout.n))
        G[0, ctx.layout.follower] = self.normal @ ctx.J_f[:3]
        gap = self.offset - self.margin - self.normal @ ctx.T_f[:3, 3]
        return dq.Constraint(G=G, h=np.array([gap / ctx.dt]), row_names=("wall",))


CONFIG = Path(__file__).resolve().parents[1] / "configs" / "puma_beam_limits.yaml"


def tool_heights(exp, result, wall):
    """Return ``normal . p`` of the follower's tool at every recorded sample [m]."""
    return np.array([wall.normal @ exp.task.follower.fk(q)[:3, 3] for q in result.trace.q_f])


if __name__ == "__main__":
    probe = dq.build_experiment(dq.load_config(CONFIG), str(CONFIG))
    start = probe.task.follower.fk(probe.initial.q_f)[:3, 3]
    wall = Wall(normal=[0.0, -1.0, 0.0], offset=-(start[1] - 0.150))  # 150 mm towards -y
    for name in dq.available_solvers():
        if name in ("reference", "fixed_grasp"):
            continue  # the paper's methods keep no limits at all
        try:
            exp = dq.build_experiment(dq.load_config(CONFIG), str(CONFIG), solver=name,
                                      limits=[wall])
        except dq.DualArmError as err:
            print(f"{name:14s} refused: {err}")
            continue
        result = dq.rollout(exp.controller(), exp.initial, duration=exp.duration,
                            limits=exp.limits)
        worst = tool_heights(exp, result, wall).max() - wall.offset
        print(f"{name:14s} {'completed' if result.completed else 'FAILED'}; the tool came "
              f"within {-worst * 1e3:.2f} mm of the wall; grasp slid "
              f"{(result.trace.grasp[0] - result.trace.grasp.min()) * 1e3:.0f} mm")
