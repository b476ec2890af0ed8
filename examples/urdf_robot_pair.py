"""Carry a bar with two robots loaded from URDF: a pair of UR5 arms.

Any serial chain of a URDF becomes an arm with ``urdf_arm(file, root, tip)``; the
robots shipped by example-robot-data load by name with ``example_robot_arm``. This
needs the ``robots`` extra: ``pip install "dualarm-qp[robots]"``.

Two UR5 arms stand 1.2 m apart, facing each other, and carry a 0.7 m bar level, 0.3 m
above their bases. The leader holds its end rigidly and carries it 240 mm towards the
follower and 120 mm sideways; the follower's grasp slides along the bar's top face.
The same task as configs/ur5_pair_sliding_bar.yaml, built in Python (SI units).

Run it with ``python examples/urdf_robot_pair.py`` (300 samples, a few seconds).
"""

import sys

import numpy as np

import dualarm_qp as dq


def pose(R: np.ndarray, p: list[float]) -> np.ndarray:
    """Return the 4x4 pose with rotation ``R`` and position ``p`` [m]."""
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = p
    return T


# The UR5 joints turn +-360 deg; the step pulls every joint towards the middle of its
# range, so narrow the ranges to an elbow-up box around the working posture [rad].
q_min = np.deg2rad([-90, -180, 0, -200, -180, -270])
q_max = np.deg2rad([90, 0, 180, 0, 0, 90])
wrist3_half_turn = np.deg2rad([0, 0, 0, 0, 0, 180])  # the follower's wrist 3 range
Rz180 = np.diag([-1.0, -1.0, 1.0])  # a half turn about z
try:
    leader = dq.example_robot_arm("ur5", root="base_link", tip="tool0",
                                  q_min=q_min, q_max=q_max, name="leader")
    follower = dq.example_robot_arm(
        "ur5", root="base_link", tip="tool0", name="follower",
        q_min=q_min + wrist3_half_turn, q_max=q_max + wrist3_half_turn,
        base=pose(Rz180, [1.2, 0.0, 0.0]))  # across the table, facing the leader
except dq.RobotModelError as err:
    sys.exit(f"urdf_robot_pair.py needs the UR5 model: {err}")
print(f"leader: {leader.n} joints {leader.joint_names}")

# Object frame: x down into the bar's top face, z along the bar towards the follower.
# The leader's hand points down with its x along the bar; the follower may grasp the
# bar from 0.2 to 0.7 m from the leader's hand.
H1 = pose(np.array([[0.0, 0.0, 1.0], [0.0, -1.0, 0.0], [1.0, 0.0, 0.0]]), [0.0, 0.0, 0.0])
bar = dq.PlaneBar(r_min=[0.0, 0.0, 0.2], r_max=[0.0, 0.0, 0.7])
Ry90 = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])
path = dq.LinearTrajectory([0.4, 0.0, 0.3], [0.08, 0.04, 0.0], R0=Ry90, tf=3.0)
task = dq.DualArmTask(leader, follower, H1, bar, path)

# Initial joints by damped least squares from elbow-up guesses [rad].
sigma0 = 0.5
q_l0 = dq.ik_dls(leader, task.leader_target(0.0),
                 np.deg2rad([-15.8, -101.1, 119.5, -108.4, -90.0, -105.8])).q
q_f0 = dq.ik_dls(follower, task.follower_target(q_l0, sigma0),
                 np.deg2rad([-21.3, -117.9, 130.0, -102.2, -90.0, 68.7])).q
initial = dq.DualArmState(t=0.0, q_l=q_l0, q_f=q_f0, sigma=sigma0)

# 10 ms samples, the URDF's joint speed limits, sliding speed <= 0.15 m/s; range
# centring over 1 s (gentler than the paper's one sample).
options = dq.StepOptions(dt=0.01, joint_weights=np.ones(6), grasp_weight=100.0,
                         grasp_speed_max=0.15, correction_gain=50.0, centre_horizon=1.0)
controller = dq.DualArmController(task, dq.get_solver("nullspace"), options,
                                  leader_gain=50.0)
result = dq.rollout(controller, initial, duration=3.0)

summary = result.summary()
print(f"completed: {result.completed} ({summary['samples']} samples)")
print(f"grasp: {summary['grasp_start_m']:.4f} m -> {summary['grasp_end_m']:.4f} m")
print(f"worst closure error: {summary['closure_pos_err_max_m'] * 1e3:.4f} mm")
