// The look-ahead's prediction (dualarm_qp/control/lookahead.py): the two pose errors one
// sample after a command, from the poses at the joints and grasp coordinates it reaches.
#pragma once

#include <vector>

#include "kinematics.hpp"

namespace dqk {

// The look-ahead's four errors one sample ahead: the object's to D(t) and the grasp
// closure's, each as the norms of the position [m] and rotation [rad] parts of
// step_errors' twelve. finite is false (and the errors zero) when x or a moved grasp
// coordinate is not finite.
struct PredictedErrors {
  bool finite = false;
  double tracking_position = 0.0, tracking_rotation = 0.0;
  double closure_position = 0.0, closure_rotation = 0.0;
};

// Moves q_l, q_f and the grasp coordinates by dt x (x: the leader's joint rates, the
// follower's, the follower's grasp speed, then the leader's if it slides), puts the
// carried-object chain's joints at the result (the leader's joints, then each grasp's
// coordinate times its rate: the leader's grasp joint first when both slide, as
// CarryModel.configuration does; col_rate holds the follower's grasp rate at n_l and the
// leader's at n_l + 1, CarryModel.columns) and returns the norms of step_errors' errors at
// those poses against T_D (not finite when x or a moved grasp coordinate is not). Every
// sum is a product then a sum, rounded as numpy rounds `q + dt * x` (the file is compiled
// without fused multiply-adds); each norm is std::hypot of its three components (Python's
// math.hypot, by another algorithm, may differ from it in the last place or two).
PredictedErrors predicted_errors(Chain& carry, const std::vector<int>& carry_frames,
                                 Chain& follower, int follower_tool, const Eigen::VectorXd& q_l,
                                 const Eigen::VectorXd& q_f, double sigma_f, double sigma_l,
                                 const Eigen::VectorXd& x, const Eigen::VectorXd& col_rate,
                                 double dt, const Pose& T_D);

// Whether the bound alone keeps a command's second-order error under share times the
// budget (dualarm_qp/control/lookahead.py, Lookahead.negligible): with the turns
// a = dt sum|x_leader|, b = dt sum|x_follower| and the grasps' travel g = dt sum|x_grasps|,
// 0.5 (a^2 (length_l + lever) + b^2 length_f) + 0.5 g^2 + a g <= share budget_pos and
// 0.5 (a^2 + b^2) <= share budget_rot, the lever being the distance from the leader's
// tool to the follower's target. Sums run left to right; the lever is the square root of
// its squares' sum (Python's math.dist, used before, may differ from it in the last
// place: only a command at the threshold itself can be decided differently).
bool negligible(const Eigen::VectorXd& x, Eigen::Index n_l, Eigen::Index n_f, double dt,
                const Pose& T_tool, const Pose& T_target,
                double length_l, double length_f, double budget_pos, double budget_rot,
                double share);

}  // namespace dqk
