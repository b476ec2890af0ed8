"""Drive the controller from your own control loop.

The controller is a per-sample function: measured state in, joint rates and sliding
speeds out. Here the "robot" is a perfect integrator; on hardware you would send
``ql_dot`` and ``qf_dot`` to the two arms' velocity interfaces and read the joints
back each sample. The task (two PUMA 560 arms carrying a beam, hard joint and sliding
speed limits) comes from configs/puma_beam_limits.yaml; see task_in_python.py for a
task built without a file.

Run it with ``python examples/own_control_loop.py`` (500 samples, a few seconds).
"""

from collections import Counter
from pathlib import Path

import numpy as np

import dualarm_qp as dq

CONFIG = Path(__file__).resolve().parents[1] / "configs" / "puma_beam_limits.yaml"

exp = dq.build_experiment(dq.load_config(CONFIG), str(CONFIG))
task, options = exp.task, exp.options
dt = options.dt  # sampling interval [s]

# One controller: the task, a solver that keeps hard limits, the step options.
controller = dq.DualArmController(task, dq.get_solver("nullspace"), options,
                                  leader_gain=exp.leader_gain)

# The measured state: path time [s], both arms' joints [rad], the grasp [m]. The
# paper's grasp starts 50 mm outside its range (Table 2): the first steps pull it back.
state = exp.initial
path_end = state.t + exp.duration
closure_max = 0.0  # worst closure error [m] over the run
travel = 0.0  # distance the grasp slid [m]
statuses: Counter[str] = Counter()

while state.t < path_end - 1e-9:
    # Never ask for more path than is left in this sample.
    out = controller.step(state, scale_max=min(1.0, (path_end - state.t) / dt))
    statuses[out.status.value] += 1
    if not out.applied:  # no usable command: stop the arms
        print(f"stopped at t = {state.t:.3f} s: {out.solution.message}")
        break
    closure_max = max(closure_max, float(np.linalg.norm(out.build.closure_error[:3])))
    travel += abs(out.m) * dt
    # Apply the command for one sample. On a robot: send the rates, then measure the
    # new state. Here: Euler integration of the rates (joints, grasps, and the path
    # time by scale * dt, scale < 1 when the limits slowed the task).
    state = state.advanced(out, dt)

print(f"steps: {sum(statuses.values())} ({dict(statuses)})")
print(f"path time reached: {state.t:.3f} of {path_end:.3f} s")
print(f"worst closure error: {closure_max * 1e3:.4f} mm")
print(f"grasp travel: {travel * 1e3:.1f} mm "
      f"({exp.initial.sigma:.4f} m -> {state.sigma:.4f} m)")
