// Both arms' kinematics of one step, in one call (StepBuilder.context): the carried
// object's chain (leader, grasp joints, object and target frames) and the follower's,
// the two pose errors of the step and the arms' smallest singular values.
#pragma once

#include <vector>

#include "kinematics.hpp"

namespace dqk {

// The error of the pose T to the target T_star: [p* - p; log3(R* R^T)] [m; rad] (the
// controller's convention, dualarm_qp/se3.py), into e (6).
void pose_error(const Pose& T_star, const Pose& T, Eigen::Ref<Eigen::VectorXd> e);

// carry.compute(q_carry, carry_frames = {tool, object, target}, the same) into T rows
// 0-11 and J (18 x nq of carry); follower.compute(q_f, {tool}, {tool}) into T rows
// 12-15 and J_f (6 x n_f); e rows 0-5 the object's error to T_D, rows 6-11 the
// follower tool's error to the target; sv (2) the smallest singular value of the
// leader's tool Jacobian (J rows 0-5, its first n_l columns) and of J_f, or sv empty:
// not computed (StepParts.prepare: the Python layer computes them when read).
void step_kinematics(Chain& carry, const Eigen::VectorXd& q_carry,
                     const std::vector<int>& carry_frames, Chain& follower,
                     const Eigen::VectorXd& q_f, int follower_tool, const Pose& T_D,
                     Eigen::Index n_l, Eigen::Ref<RowMat> T, Eigen::Ref<RowMat> J,
                     Eigen::Ref<RowMat> J_f, Eigen::Ref<Eigen::VectorXd> e,
                     Eigen::Ref<Eigen::VectorXd> sv);

// The same two pose errors into e (12) from the poses alone (no Jacobians, Chain::poses_at:
// the chains' kinematics stay those of their last update): the look-ahead's prediction at
// the next sample (dualarm_qp/control/lookahead.py).
void step_errors(Chain& carry, const Eigen::VectorXd& q_carry,
                 const std::vector<int>& carry_frames, Chain& follower,
                 const Eigen::VectorXd& q_f, int follower_tool, const Pose& T_D,
                 Eigen::Ref<Eigen::VectorXd> e);

}  // namespace dqk
