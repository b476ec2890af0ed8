"""Add a task of your own: hold the follower's elbow near its start, in the null space.

A task is a small object with a ``name``, a ``weight`` and one method,
``equality(ctx)``, that returns rows ``A x = b`` over the decision vector ``x``
(``dualarm_qp.step.parts``). With ``weight = None`` the rows are equalities of the step,
held exactly like the object's path and the grasp closure. With a number, they are a
term ``weight |A x - b|^2`` of the cost: the step then meets them as far as the
equalities and every limit let it, here with the freedom the sliding grasp leaves (the
paper's seventh degree of freedom).

The task asks the follower's elbow joint ``qf3`` to move back towards its starting
angle ``q*`` at a rate ``gain (q* - qf3)`` [rad/s]. On the paper's beam task the elbow
otherwise turns by 31 degrees while the grasp slides 308 mm; with the task the elbow
stays within a degree and the grasp slides half as far, while the object still
follows D(t), the grasp stays closed and every hard limit holds. A weighted task makes
the step's cost a full matrix: a solver that takes a diagonal cost only (SNS) is
refused before anything runs.

Run it with ``python examples/custom_task.py``.
"""

from pathlib import Path

import numpy as np

import dualarm_qp as dq


class HoldJoint:
    """The follower's joint ``joint`` moves back to ``q_star`` (a weighted task, one row)."""

    name = "hold the elbow"

    def __init__(self, joint, q_star, gain=5.0, weight=1e4):
        self.joint, self.q_star = int(joint), float(q_star)  # index, [rad]
        self.gain, self.weight = float(gain), weight  # [1/s], [1/(rad/s)^2]

    def equality(self, ctx):
        """One row: ``qf_dot[joint] = gain (q_star - qf[joint])``."""
        A = np.zeros((1, ctx.layout.n))
        A[0, ctx.layout.follower.start + self.joint] = 1.0
        b = np.array([self.gain * (self.q_star - ctx.state.q_f[self.joint])])
        return dq.Equality(A, b, (f"hold qf{self.joint + 1}",))


CONFIG = Path(__file__).resolve().parents[1] / "configs" / "puma_beam_limits.yaml"
ELBOW = 2  # qf3


def run(with_task: bool):
    """Return the experiment and its run, with or without the task."""
    probe = dq.build_experiment(dq.load_config(CONFIG), str(CONFIG))
    tasks = [HoldJoint(ELBOW, probe.initial.q_f[ELBOW])] if with_task else []
    exp = dq.build_experiment(dq.load_config(CONFIG), str(CONFIG), tasks=tasks)
    return exp, dq.rollout(exp.controller(), exp.initial, duration=exp.duration,
                           limits=exp.limits)


if __name__ == "__main__":
    for with_task in (False, True):
        exp, result = run(with_task)
        turn = np.degrees(np.abs(result.trace.q_f[:, ELBOW] - exp.initial.q_f[ELBOW]).max())
        print(f"{'with' if with_task else 'without'} the task: "
              f"{'completed' if result.completed else 'FAILED'}; the elbow turned at most "
              f"{turn:.1f} deg; the grasp slid "
              f"{(result.trace.grasp[0] - result.trace.grasp.min()) * 1e3:.0f} mm")
