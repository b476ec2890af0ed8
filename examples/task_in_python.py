"""Build a carrying task in Python, without a YAML file, and run it.

Two PUMA 560 arms carry a 0.4 m bar along a straight line: the paper's beam example
with the PUMA's joint speed limits and a 0.1 m/s sliding speed limit. The leader holds
one end of the bar rigidly; the follower's grasp slides along the bar. Everything is
in SI units (m, rad, s).

Run it with ``python examples/task_in_python.py`` (160 samples, a few seconds).
"""

import numpy as np

import dualarm_qp as dq

# The arms. The world frame is the leader's base frame; the follower's base stands
# 1.38 m away along y (the base the paper's example implies, docs/reproduction.md).
T_world_follower_base = np.eye(4)
T_world_follower_base[:3, 3] = [0.3, 1.38, 0.0]
leader = dq.puma560(name="leader")
follower = dq.puma560(base=T_world_follower_base, name="follower")

# The object: a bar whose frame is the leader's hand frame (H1 = identity). The
# follower's grasp slides along the bar's z axis, from 0 to 0.4 m (the paper's Fig. 4).
bar = dq.PlaneBar(r_min=[0.0, 0.0, 0.0], r_max=[0.0, 0.0, 0.4])

# The desired object path D(t): constant orientation, 32 mm/s along x for 5 s.
R0 = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])
path = dq.LinearTrajectory([-0.0003, 0.690, 0.2604], [1 / 31, 0.0, 0.0], R0=R0, tf=5.0)

task = dq.DualArmTask(leader, follower, H1=np.eye(4), surface=bar, trajectory=path)

# Initial joints: the leader's hand at D(0), the follower's hand on the grasp at
# sigma0 = 0.35 m. Damped least squares from a nearby guess [rad].
sigma0 = 0.35
q_l0 = dq.ik_dls(leader, task.leader_target(0.0),
                 np.deg2rad([76.4, 16.6, 13.9, 15.7, 60.5, 172.1])).q
q_f0 = dq.ik_dls(follower, task.follower_target(q_l0, sigma0),
                 np.deg2rad([-150.0, 32.0, -31.0, 0.0, -1.0, -106.0])).q
initial = dq.DualArmState(t=0.0, q_l=q_l0, q_f=q_f0, sigma=sigma0)

# The step problem: 31 ms samples; follower joint weights 1 [1/(rad/s)^2] and the
# sliding weight s7 = 100 [1/(m/s)^2]; joint speed limits on, sliding speed <= 0.1 m/s.
options = dq.StepOptions(dt=0.031, joint_weights=np.ones(6), grasp_weight=100.0,
                         velocity_limits=True, grasp_speed_max=0.1)

# A solver that keeps hard limits (exact, by null-space parametrisation), and the
# controller that steps it; rollout integrates it along the whole path.
controller = dq.DualArmController(task, dq.get_solver("nullspace"), options)
result = dq.rollout(controller, initial, duration=path.tf - path.t0)

summary = result.summary()
print(f"completed: {result.completed} ({summary['samples']} samples)")
print(f"grasp: {summary['grasp_start_m']:.4f} m -> {summary['grasp_end_m']:.4f} m")
print(f"worst closure error: {summary['closure_pos_err_max_m'] * 1e3:.4f} mm")
print(f"worst follower speed ratio: {result.realised['follower'].speed_ratio:.3f}")
